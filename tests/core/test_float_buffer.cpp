// The storage of volumes and projection stacks: large buffers start on a 2 MB boundary (so the
// kernel can back them with huge pages), small ones on a cache line; both behave as vectors.
#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <numeric>
#include <sstream>
#include <string>

#include "ctk/core/float_buffer.hpp"
#include "ctk/core/projection_stack.hpp"
#include "ctk/core/volume.hpp"

namespace ctk {
namespace {

std::uintptr_t address(const float* p) { return reinterpret_cast<std::uintptr_t>(p); }

// The kernel's "THPeligible" flag of the mapping holding p (-1 when /proc tells nothing).
int huge_page_eligible(const float* p) {
  std::ifstream smaps("/proc/self/smaps");
  std::string line;
  bool inside = false;
  while (std::getline(smaps, line)) {
    std::uintptr_t begin = 0, end = 0;
    char dash = 0;
    std::istringstream head(line);
    if (head >> std::hex >> begin >> dash >> end && dash == '-') {
      inside = begin <= address(p) && address(p) < end;
      continue;
    }
    if (inside && line.rfind("THPeligible:", 0) == 0) return std::stoi(line.substr(12));
  }
  return -1;
}

bool huge_pages_never() {
  std::ifstream mode("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string text;
  std::getline(mode, text);
  return text.empty() || text.find("[never]") != std::string::npos;
}

TEST(FloatBuffer, LargeBuffersStartOnAHugePageAndSmallOnesOnACacheLine) {
  const FloatBuffer large(std::size_t{3} << 20, 0.0f);  // 12 MB
  EXPECT_EQ(address(large.data()) % detail::kHugePageBytes, 0u);
  const FloatBuffer just_large(detail::kHugePageBytes / sizeof(float), 0.0f);
  EXPECT_EQ(address(just_large.data()) % detail::kHugePageBytes, 0u);
  const FloatBuffer small(1000, 0.0f);
  EXPECT_EQ(address(small.data()) % 64, 0u);
}

// With transparent huge pages in "madvise" mode a mapping is eligible only if it was advised.
TEST(FloatBuffer, TheKernelMayBackLargeBuffersWithHugePages) {
  const FloatBuffer large(std::size_t{3} << 20, 0.0f);
  EXPECT_EQ(huge_page_eligible(large.data()), huge_pages_never() ? 0 : 1);
}

TEST(FloatBuffer, BehavesAsAVectorAcrossTheHugePageThreshold) {
  FloatBuffer v(10, 1.0f);
  v.resize(std::size_t{1} << 20);  // 4 MB: moves from the small to the large path
  EXPECT_EQ(v[9], 1.0f);
  EXPECT_EQ(v[10], 0.0f);
  EXPECT_EQ(v.back(), 0.0f);
  std::iota(v.begin(), v.end(), 0.0f);
  const FloatBuffer copy = v;
  EXPECT_EQ(copy[123456], 123456.0f);
  v.resize(5);  // shrinking keeps the values; shrink_to_fit goes back to the small path
  v.shrink_to_fit();
  EXPECT_EQ(v[4], 4.0f);
  EXPECT_EQ(address(v.data()) % 64, 0u);
}

TEST(FloatBuffer, VolumesAndStacksUseIt) {
  const Volume volume(VolumeLayout::centred({128, 128, 64}, Eigen::Vector3d::Ones()));  // 4 MB
  EXPECT_EQ(address(volume.data.data()) % detail::kHugePageBytes, 0u);
  EXPECT_EQ(volume.at(127, 127, 63), 0.0f);
  const ProjectionStack stack(10, 256, 256);  // 2.5 MB
  EXPECT_EQ(address(stack.data.data()) % detail::kHugePageBytes, 0u);
}

}  // namespace
}  // namespace ctk
