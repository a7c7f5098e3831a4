#include "ctk/core/output_set.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "ctk/core/atomic_write.hpp"
#include "ctk/core/cancellation.hpp"

namespace ctk {
namespace {

namespace fs = std::filesystem;

fs::path fresh_folder(const std::string& name) {
  fs::path dir = fs::temp_directory_path() / ("ctk-output-set-" + name + "-" + this_run_id());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  return {std::istreambuf_iterator<char>(in), {}};
}

int entries(const fs::path& dir) {
  return static_cast<int>(std::distance(fs::directory_iterator(dir), fs::directory_iterator()));
}

// Clears the process' stop request whatever a test does, so the next test starts without one.
struct StopRequestCleared {
  StopRequestCleared() { clear_stop_request(); }
  ~StopRequestCleared() { clear_stop_request(); }
};

TEST(OutputSet, HoldsEveryFileUntilPublishedThenRenamesThemAll) {
  const fs::path dir = fresh_folder("publish");
  {
    OutputSet outputs;
    write_text_atomically(dir / "matrices.json", "m");
    write_text_atomically(dir / "scan.json", "s");
    EXPECT_FALSE(fs::exists(dir / "matrices.json"));
    EXPECT_FALSE(fs::exists(dir / "scan.json"));
    EXPECT_EQ(read_text(outputs.current(dir / "scan.json")), "s");
    outputs.publish();
  }
  EXPECT_EQ(read_text(dir / "matrices.json"), "m");
  EXPECT_EQ(read_text(dir / "scan.json"), "s");
  EXPECT_EQ(entries(dir), 2);  // no temporary left
  fs::remove_all(dir);
}

TEST(OutputSet, PublishesNothingWhenAStopWasRequestedBeforePublishing) {
  const StopRequestCleared cleared;
  const fs::path dir = fresh_folder("stopped");
  write_text_atomically(dir / "scan.json", "older");
  {
    OutputSet outputs;
    write_text_atomically(dir / "matrices.json", "m");
    write_text_atomically(dir / "scan.json", "newer");
    request_stop();
    EXPECT_THROW(outputs.publish(), Cancelled);
  }
  EXPECT_EQ(read_text(dir / "scan.json"), "older");
  EXPECT_FALSE(fs::exists(dir / "matrices.json"));
  EXPECT_EQ(entries(dir), 1);  // the set's temporaries removed with it
  fs::remove_all(dir);
}

// A front end that sees a stop late (Python's main thread) is asked on the publishing thread, and
// only there; a stop it finds then still publishes nothing.
TEST(OutputSet, AsksThePublishingThreadsCheckForALateStop) {
  const StopRequestCleared cleared;
  const fs::path dir = fresh_folder("late");
  int asked_here = 0, asked_elsewhere = 0;
  std::thread elsewhere([&] {
    const PublishCheck other([&] { ++asked_elsewhere; });
    OutputSet outputs;
    write_text_atomically(dir / "first.json", "1");
    outputs.publish();
  });
  elsewhere.join();
  EXPECT_EQ(asked_elsewhere, 1);
  {
    const PublishCheck look([&] {
      ++asked_here;
      request_stop();
    });
    OutputSet outputs;
    write_text_atomically(dir / "second.json", "2");
    EXPECT_THROW(outputs.publish(), Cancelled);
  }
  EXPECT_EQ(asked_here, 1);
  EXPECT_EQ(asked_elsewhere, 1);
  EXPECT_TRUE(fs::exists(dir / "first.json"));
  EXPECT_FALSE(fs::exists(dir / "second.json"));
  EXPECT_EQ(entries(dir), 1);
  fs::remove_all(dir);
}

TEST(StagedFolder, LeavesTheTargetAsItWasWhenAStopWasRequestedBeforeTheSwap) {
  const StopRequestCleared cleared;
  const fs::path dir = fresh_folder("staged");
  fs::create_directories(dir / "scan");
  write_text_atomically(dir / "scan" / "scan.json", "older");
  {
    StagedFolder staged(dir / "scan", {"scan.json"});
    write_text_atomically(staged.path() / "scan.json", "newer");
    request_stop();
    EXPECT_THROW(staged.commit(), Cancelled);
  }
  EXPECT_EQ(read_text(dir / "scan" / "scan.json"), "older");
  EXPECT_EQ(entries(dir), 1);  // the hidden folder removed
  clear_stop_request();
  {
    StagedFolder staged(dir / "scan", {"scan.json"});
    write_text_atomically(staged.path() / "scan.json", "newer");
    staged.commit();
  }
  EXPECT_EQ(read_text(dir / "scan" / "scan.json"), "newer");
  fs::remove_all(dir);
}

// A folder handed to the run's set arrives with its files, and not at all when they do not.
TEST(StagedFolder, HandedToTheRunsSetArrivesWithItsFilesOrNotAtAll) {
  const fs::path dir = fresh_folder("with-set");
  for (const bool published : {false, true}) {
    OutputSet outputs;
    auto frames = std::make_unique<StagedFolder>(dir / "scan.frames", std::vector<std::string>{});
    {
      const OutputSet::Outside now;  // into the hidden folder at once, as an import writes its frames
      write_text_atomically(frames->path() / "proj_00000.tif", "frame");
    }
    commit_with_outputs(std::move(frames));
    write_text_atomically(dir / "scan.json", "names the frames");
    EXPECT_FALSE(fs::exists(dir / "scan.frames"));
    if (published) outputs.publish();
  }
  EXPECT_EQ(read_text(dir / "scan.frames" / "proj_00000.tif"), "frame");
  EXPECT_EQ(read_text(dir / "scan.json"), "names the frames");
  EXPECT_EQ(entries(dir), 2);  // the unpublished run's hidden folder gone
  fs::remove_all(dir);
}

}  // namespace
}  // namespace ctk
