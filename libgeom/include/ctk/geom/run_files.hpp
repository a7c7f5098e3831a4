#pragma once
// What a run reads and what it will write, each named by the option or key it came from. Before
// any work a command lists both and calls check(): an output that is one of the inputs, or that
// another output of the same run also names, is refused with both names (exit 2), whether the two
// paths differ by `..`, a relative form, a symbolic link or a hard link.
#include <filesystem>
#include <string>
#include <vector>

namespace ctk {

struct ScanDescription;

class RunFiles {
 public:
  void input(std::string what, const std::filesystem::path& file);
  /// Every file a scan reads: the scan file itself, its projections, flats, darks, joint log and
  /// matrices.
  void scan(const std::string& what, const std::filesystem::path& scan_file, const ScanDescription& scan);
  /// The same for a scan whose projections the run reads: its declared count is first checked
  /// against the files (require_projection_files, InputError naming projections.count), before a
  /// name per view is listed or any structure per view built.
  void scan_to_read(const std::string& what, const std::filesystem::path& scan_file, const ScanDescription& scan);
  /// Every file below `folder` is input (a folder the run reads from).
  void input_folder(std::string what, const std::filesystem::path& folder);

  void output(std::string what, const std::filesystem::path& file);
  /// The run writes files of its own naming into `folder`: no input may lie in it.
  void output_folder(std::string what, const std::filesystem::path& folder);
  /// The run writes files named `prefix*suffix` (pictures numbered by view, ...).
  void output_family(std::string what, const std::filesystem::path& prefix, const std::string& suffix);

  /// Throws InputError naming the output (file and option) and what it would overwrite.
  void check() const;

 private:
  struct Entry {
    std::string what;
    std::filesystem::path path;   // as given
    std::filesystem::path place;  // absolute, `..` and symbolic links resolved
    std::string suffix;           // families only
  };
  std::vector<Entry> inputs_, input_folders_, outputs_, output_folders_, families_;
};

}  // namespace ctk
