#pragma once
// Helpers shared by the test suites: a fresh scratch folder per test, small file writers, and the
// check of an options struct refusing a field out of range.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

namespace ctk::testing {

/// A folder under the build tree named after the running test, emptied on creation.
inline std::filesystem::path scratch_dir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::filesystem::path dir =
      std::filesystem::path(CTK_TEST_TMP_DIR) / (std::string(info->test_suite_name()) + "." + info->name());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

inline void write_text(const std::filesystem::path& file, const std::string& text) { std::ofstream(file) << text; }

inline std::filesystem::path shared_data_dir() { return CTK_SHARED_DATA_DIR; }

/// `options` spoiled by `spoil` must fail its validate() with a message naming `field`
/// ("SirtOptions.relaxation: expected ...").
template <typename Options, typename Spoil>
void expect_option_refused(Options options, Spoil spoil, const std::string& field) {
  spoil(options);
  try {
    options.validate();
    ADD_FAILURE() << field << " out of range was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(field + ": expected"), std::string::npos) << e.what();
  }
}

}  // namespace ctk::testing
