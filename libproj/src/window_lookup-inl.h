// Per SIMD target: picking lanes out of a window of 2N neighbouring floats (two vectors) by
// index, the gather-free read both the Joseph row window and the voxel-driven back projection
// use where their lanes fall close together.
#if defined(CTK_PROJ_WINDOW_LOOKUP_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef CTK_PROJ_WINDOW_LOOKUP_INL_H_
#undef CTK_PROJ_WINDOW_LOOKUP_INL_H_
#else
#define CTK_PROJ_WINDOW_LOOKUP_INL_H_
#endif

#include <hwy/highway.h>

#include <cstdint>

HWY_BEFORE_NAMESPACE();
namespace ctk::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// Lanes of `lo` (pos < N) or `hi` (pos - N otherwise), pos in [0, 2N): a two-table permute.
template <class DF>
HWY_INLINE hn::Vec<DF> lookup_window(DF df, hn::Vec<DF> lo, hn::Vec<DF> hi, hn::Vec<hn::RebindToSigned<DF>> pos) {
#if HWY_TARGET <= HWY_AVX3
  (void)df;
  return hn::Vec<DF>{_mm512_permutex2var_ps(lo.raw, pos.raw, hi.raw)};
#else
  const hn::RebindToSigned<DF> di;
  const auto n = hn::Set(di, static_cast<std::int32_t>(hn::Lanes(df)));
  const auto idx = hn::IndicesFromVec(df, hn::And(pos, hn::Sub(n, hn::Set(di, 1))));
  return hn::IfThenElse(hn::RebindMask(df, hn::Lt(pos, n)), hn::TableLookupLanes(lo, idx), hn::TableLookupLanes(hi, idx));
#endif
}

}  // namespace HWY_NAMESPACE
}  // namespace ctk::detail
HWY_AFTER_NAMESPACE();

#endif
