#pragma once
// A run's outputs published together. While an OutputSet lives, every write_*_atomically of the
// process writes under a temporary name and waits; publish() renames them all into place in the
// order they were written, so the file written last (the one a reader opens first) arrives last.
// A run that fails or is interrupted before publish() leaves nothing: not one new file beside
// older ones; publish() itself throws Cancelled, publishing nothing, when a stop was requested
// (cancellation.hpp). A StagedFolder does the same for a folder written whole (a simulated scan): the run
// writes into a hidden folder beside the target, which is swapped in at once.
//
// Temporary names carry the run's identity (host, process, start time, random), so two runs on
// two hosts writing into one shared folder never write into each other's temporaries; those a
// killed run of this host left are removed by the next run that writes the same target.
#include <filesystem>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

namespace ctk {

/// host-pid-yyyymmddThhmmss-random: unique across processes and hosts.
const std::string& this_run_id();

/// `.<stem>.<run id>-<n><extension>` beside `path`: same folder (rename is atomic), same
/// extension (format-by-extension writers pick the right format).
std::filesystem::path temporary_beside(const std::filesystem::path& path);

class StagedFolder;

class OutputSet {
 public:
  OutputSet();   // becomes the process' active set; one at a time
  ~OutputSet();  // removes whatever was written and not published
  OutputSet(const OutputSet&) = delete;
  OutputSet& operator=(const OutputSet&) = delete;

  /// Swaps every waiting folder in, then renames every waiting file into place, in the order
  /// written; a file written twice is published once, at its last version.
  void publish();
  /// The set the atomic writers wait in, or nullptr.
  static OutputSet* active();
  /// Called by the atomic writers: `temporary` is complete and waits to become `target`.
  void add(std::filesystem::path temporary, std::filesystem::path target);
  /// A folder written whole that waits for publish(), which swaps it in before the files (a scan
  /// naming its frames arrives after them); removed with the set when it is not published.
  void add(std::unique_ptr<StagedFolder> folder);
  /// Where `target`'s content is now: its temporary while it waits in this set, else `target`.
  std::filesystem::path current(const std::filesystem::path& target);

  /// While one lives, atomic writes of this process are renamed at once, not held for the set (a
  /// solver's saved state, which must outlive an interrupted run).
  class Outside {
   public:
    Outside();
    ~Outside();
    Outside(const Outside&) = delete;
    Outside& operator=(const Outside&) = delete;

   private:
    OutputSet* held_;
  };

 private:
  std::mutex mutex_;
  std::vector<std::unique_ptr<StagedFolder>> folders_;
  std::vector<std::pair<std::filesystem::path, std::filesystem::path>> waiting_;  // temporary, target
};

class StagedFolder {
 public:
  /// Creates the hidden folder beside `target` that the run writes into. `owned`: the top-level
  /// names this kind of run writes (an earlier run's versions of them are replaced as a whole).
  StagedFolder(std::filesystem::path target, std::vector<std::string> owned);
  ~StagedFolder();  // removes the hidden folder unless committed
  StagedFolder(const StagedFolder&) = delete;
  StagedFolder& operator=(const StagedFolder&) = delete;

  const std::filesystem::path& path() const { return staging_; }
  /// Puts the written folder at the target in one step (an existing target is exchanged with it
  /// atomically), then moves into it the old folder's entries not `owned` (a user's notes, an
  /// earlier reconstruction), and removes the rest of the old folder.
  void commit();

 private:
  friend class OutputSet;
  void swap_in();  // commit() past the last look for a stop

  std::filesystem::path target_, place_, staging_;  // as given; resolved; the hidden folder
  std::vector<std::string> owned_;
  bool committed_ = false;
};

/// `folder` committed with the run's outputs by the active set's publish(), or now when no set is
/// active.
void commit_with_outputs(std::unique_ptr<StagedFolder> folder);

}  // namespace ctk
