#pragma once
// Runs a check on every SIMD target this CPU runs (AVX-512, AVX2, SSE4, ...), not only the one
// dispatch picks: the kernels' windows are 2 x lanes wide and their paths differ by target.
#include <gtest/gtest.h>

#include <string>

#include "ctk/proj/joseph_projector.hpp"

namespace ctk::testing {

// The fallbacks too (SSSE3, SCALAR): ctk bench --simd may choose them, and SCALAR's one lane
// takes paths of its own.
template <typename Check>
void on_every_simd_target(Check&& check) {
  for (const std::string& target : JosephProjector::simd_targets()) {
    JosephProjector::use_simd_target(target);
    SCOPED_TRACE(target);
    check();
  }
  JosephProjector::use_simd_target("");  // back to the widest
}

}  // namespace ctk::testing
