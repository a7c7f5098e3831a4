#pragma once
// Helpers shared by the test suites: a fresh scratch folder per test, and small file writers.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
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

inline void write_text(const std::filesystem::path& file, const std::string& text) {
  std::ofstream(file) << text;
}

inline std::filesystem::path shared_data_dir() { return CTK_SHARED_DATA_DIR; }

}  // namespace ctk::testing
