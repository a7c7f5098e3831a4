#pragma once
// Runs a check on every SIMD target this CPU runs (AVX-512, AVX2, SSE4), not only the one
// dispatch picks: the kernels' windows are 2 x lanes wide and their paths differ by target.
#include <gtest/gtest.h>
#include <hwy/targets.h>

#include <cstdint>

#include "ctk/proj/joseph_projector.hpp"

namespace ctk::testing {

template <typename Check>
void on_every_simd_target(Check&& check) {
  const std::int64_t supported = hwy::SupportedTargets();
  for (const std::int64_t target : {HWY_AVX3, HWY_AVX2, HWY_SSE4}) {
    if ((supported & target) == 0) continue;
    hwy::SetSupportedTargetsForTest(target);
    SCOPED_TRACE(JosephProjector::simd_target());
    check();
  }
  hwy::SetSupportedTargetsForTest(0);  // back to what the CPU has
}

}  // namespace ctk::testing
