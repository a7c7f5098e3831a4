// SIMD kernels of the fast Joseph projector, compiled once per x86 target by Highway and chosen
// at run time. Lanes are neighbouring rays; each lane carries its own axis, strides and range.
// Here bundles of lanes are marched slice by slice; where one sample falls and how it reads and
// writes its corners is in joseph_samples-inl.h, the forward projection's gather-free row window
// in joseph_row_window-inl.h, the tiles that rays along x march through in joseph_tiles-inl.h,
// and the bands the back projection adds through in joseph_bands-inl.h.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "joseph_kernels.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include <algorithm>
#include <vector>

#include "joseph_bands-inl.h"
#include "joseph_row_window-inl.h"
#include "joseph_samples-inl.h"
#include "joseph_tiles-inl.h"
#include "ray_table.hpp"

HWY_BEFORE_NAMESPACE();
namespace ctk::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// `sum` plus the forward samples of bundle b over slices [k_lo, k_hi] in order, not yet times
// the path length.
template <class DF>
HWY_INLINE hn::Vec<DF> march_forward(DF df, const RayTable& t, const float* HWY_RESTRICT volume, const Bundle& b, int k_lo,
                                     int k_hi, hn::Vec<DF> sum, Rows fetch) {
  const auto all = hn::FirstN(df, hn::Lanes(df));
  for (int k = k_lo; k <= k_hi; ++k) {
    if (k >= b.in_lo && k <= b.in_hi) {
      if (b.window) {  // every interior slice of this call at once
        const int last = std::min(k_hi, b.in_hi);
        sum = add_window_samples(df, t, volume, b.r, k, last, sum, fetch);
        k = last;
        continue;
      }
      const auto c = interior_corners_at(df, t, b.r, k);
      sum = hn::Add(sum, b.pairs ? interpolate_pairs(df, volume, c) : interpolate(df, volume, c));
    } else if (b.pairs) {  // every rim slice up to the interior or the end
      const int last = k < b.in_lo ? std::min(k_hi, b.in_lo - 1) : k_hi;
      sum = add_rim_samples(df, t, volume, b, k, last, sum, fetch);
      k = last;
    } else {
      hn::Vec<DF> sample;
      if (!b.window || !interpolate_window(df, t, volume, b.r, k, sample))
        sample = interpolate(df, volume, corners_at(df, t, b.r, k, all).corners);
      sum = hn::Add(sum, sample);
    }
  }
  return sum;
}

// volume += the adjoint of march_forward for `value` (already times the path length), for the
// lanes in `lanes`. The interior slices go lane by lane through scatter_add_interior_slices on
// every target, the masked ones (on the rim, or with lanes of other axes) through
// scatter_add_rim_slices. (AVX-512 had a row window for them, placing the lanes' weights by expand and
// permutes and updating the rows whole, one slice at a time: on the Zen 4 it took 1.12-1.3x
// longer than this scatter, with or without its rows asked for ahead; benchmarks/paired.py.)
template <class DF>
HWY_INLINE void march_back(DF df, const RayTable& t, const Bundle& b, hn::Vec<DF> value, hn::Mask<DF> lanes, int k_lo, int k_hi,
                           float* HWY_RESTRICT volume, Rows fetch) {
  for (int k = k_lo; k <= k_hi; ++k) {
    if (k >= b.in_lo && k <= b.in_hi) {  // every interior slice of this call at once
      const int last = std::min(k_hi, b.in_hi);
      scatter_add_interior_slices(df, t, b.r, k, last, value, volume, fetch);
      k = last;
    } else {  // every masked slice up to the interior or the end
      const int last = k < b.in_lo ? std::min(k_hi, b.in_lo - 1) : k_hi;
      scatter_add_rim_slices(df, t, b, k, last, lanes, value, volume, fetch);
      k = last;
    }
  }
}

// One strip's bundles along x (kStripColumns neighbouring columns of every row of the table),
// and how each is marched through a tile or (where the tile would be too large) through the
// volume.
struct XStrip {
  // Room for the bundles of a strip of kLinesAcrossRows lines (96 on AVX-512, 192 on AVX2, 384
  // on SSE4) and no fewer than 128; bundles beyond that march in the volume.
  static constexpr int kMaxBundles = std::clamp(kStripColumns * kLinesAcrossRows, 128, 384);
  int count = 0;
  std::size_t entries[kMaxBundles];  // in the table
  Bundle tile[kMaxBundles];          // the same bundles in `local`, addressing the tile
  int k_lo = 0, k_hi = -1;           // slices any of them visits
  // The same bundles in the volume (for tiles too large), found when first needed.
  Bundle volume[kMaxBundles];
  bool volume_found = false;
};

// The rays at entry r of `t` copied to entry `to` of `local`: what a march through a tile reads
// of them, their positions and their slice ranges [first, last] (loaded from `t` by the caller,
// which needs them too; address_tile sets the grid; weights and values are read from `t`). In a
// tile every corner of a lane in its range is there, so a lane's interior range is its range. One
// vector per array: copying all seventeen arrays with std::copy_n, once per slab task, was 5 % of
// a circular back projection in memmove calls on the Zen 5 (benchmarks/paired.py).
template <class DF, class VI = hn::Vec<hn::RebindToSigned<DF>>>
HWY_INLINE void copy_rays(DF df, const RayTable& t, std::size_t r, VI first, VI last, RayTable& local, std::size_t to) {
  const hn::RebindToSigned<DF> di;
  for (auto ray : {&RayTable::pb_mid, &RayTable::beta_b, &RayTable::pc_mid, &RayTable::beta_c, &RayTable::k_mid})
    hn::StoreU(hn::LoadU(df, (t.*ray).data() + r), df, (local.*ray).data() + to);
  hn::StoreU(first, di, local.k_first.data() + to);
  hn::StoreU(first, di, local.in_first.data() + to);
  hn::StoreU(last, di, local.k_last.data() + to);
  hn::StoreU(last, di, local.in_last.data() + to);
}

// Copies the strip's bundles into `local` (row i for bundle i) and finds where they march.
template <class DF>
HWY_INLINE void prepare_strip(DF df, const RayTable& t, XStrip& s, RayTable& local) {
  const hn::RebindToSigned<DF> di;
  const auto far = hn::Set(di, 1 << 30);
  s.k_lo = 1 << 30;
  s.k_hi = -(1 << 30);
  for (int i = 0; i < s.count; ++i) {
    const std::size_t r = s.entries[i];
    Bundle& b = s.tile[i];
    b.r = local.entry(0, i, 0);
    const auto first = hn::LoadU(di, t.k_first.data() + r), last = hn::LoadU(di, t.k_last.data() + r);
    copy_rays(df, t, r, first, last, local, b.r);
    // In a tile the fast path needs only that every lane be in its range: max and min over lanes.
    b.in_lo = hn::GetLane(hn::MaxOfLanes(di, first));
    b.in_hi = hn::GetLane(hn::MinOfLanes(di, last));
    // Slices any lane visits: min and max over lanes that visit any.
    const auto visits = hn::Not(hn::Lt(last, first));
    b.k_lo = hn::GetLane(hn::MinOfLanes(di, hn::IfThenElse(visits, first, far)));
    b.k_hi = hn::GetLane(hn::MaxOfLanes(di, hn::IfThenElse(visits, last, hn::Neg(far))));
    b.pairs = true;
    b.window = hn::Lanes(df) >= 4;
    s.k_lo = std::min(s.k_lo, b.k_lo);
    s.k_hi = std::max(s.k_hi, b.k_hi);
  }
  s.volume_found = false;
}

// What a kernel call needs to march strips along x: the strip, copies of its rays, a tile.
struct StripWorkspace {
  XStrip strip;
  RayTable local;
  std::vector<float> tile_data;
  // Kept from call to call (each thread's own and each target's, thread_local below, so `lanes`
  // never changes): shaping the copies and sizing the tile (value-initialising 384 kB) on every
  // call cost 1-2 % of each projection (benchmarks/paired.py).
  void reserve(int rows, int lanes) {
    const int bundles = std::min(rows * kStripColumns, XStrip::kMaxBundles);
    if (local.rows != bundles) local.shape(1, bundles, lanes);
    tile_data.resize(static_cast<std::size_t>(kTileSlices * kTileMaxHeight * kTileMaxWidth));
  }
};

HWY_INLINE const Bundle* volume_bundles(const RayTable& t, std::size_t lanes, int axis, XStrip& s) {
  if (!s.volume_found)
    for (int i = 0; i < s.count; ++i) s.volume[i] = bundle_at(t, s.entries[i], lanes, axis);
  s.volume_found = true;
  return s.volume;
}

// The volume's grid as the strip's rays along x see it, from a lane that runs along x: lanes
// that miss the volume may carry another axis (or none), and along_x admits them.
HWY_INLINE XGrid x_grid(const RayTable& t, std::size_t bundle, std::size_t lanes) {
  for (std::size_t l = 0; l < lanes; ++l) {
    const std::size_t r = bundle + l;
    if (t.axis[r] == 0 && t.k_first[r] <= t.k_last[r]) return {t.stride_b[r], t.stride_c[r], t.n_b[r], t.n_c[r]};
  }
  return {};  // unreachable: along_x requires such a lane
}
HWY_INLINE XGrid x_grid(const RayTable& t, const XStrip& s, std::size_t lanes) { return x_grid(t, s.entries[0], lanes); }

// Slices [k_begin, k_end) in chunks of up to kTileSlices, aligned so that each tile row is one
// cache line where the slab allows.
template <class F>
HWY_INLINE void for_each_chunk(int k_lo, int k_hi, int k_begin, int k_end, F&& f) {
  const int lo = std::max(k_lo, k_begin), hi = std::min(k_hi, k_end - 1);
  for (int k0 = lo / kTileSlices * kTileSlices; k0 <= hi; k0 += kTileSlices)
    f(std::max(k0, lo), std::min(k0 + kTileSlices - 1, hi));
}

// Bundles not along x march through the volume itself, every bundle of the table chunk by chunk
// of this many slices rather than one bundle over all its slices after another. The table's
// lines cross neighbouring rows of each slice, so a chunk's rows are read (or written) by
// several lines while they are still in L1/L2; one bundle at a time, the rows a line shared with
// the one before had been evicted by then (slices along z are 256 kB apart in a 256^3 volume, so
// no prefetcher foresees the next). Per-bundle state stays in registers over a chunk; one slice
// at a time it did not (25 % slower). Measured on Zen 3, benchmarks/README.md (benchmarks/paired.py).
// The forward projection takes 16: each bundle's call then makes one full pass of
// add_window_samples, whose set-up costs about 300 instructions (1.01-1.13x over 8, benchmarks/paired.py);
// the back projection measured no better with 16 (0.97-1.01) and keeps 8.
constexpr int kForwardChunkSlices = 16;
constexpr int kBackChunkSlices = 8;

// The tile for slices [k0, k1] of the strip, its rays' copies pointed at it; the bundles in
// the volume instead when it would be too large (null when it fits).
template <class DF>
HWY_INLINE TileFit start_chunk(DF df, const RayTable& t, int axis, int k0, int k1, StripWorkspace& w, Tile& tile,
                               const Bundle*& in_volume) {
  const TileFit fit = tile_box(df, t, w.strip.entries, w.strip.count, k0, k1, tile);
  in_volume = nullptr;
  if (fit == TileFit::too_large) in_volume = volume_bundles(t, hn::Lanes(df), axis, w.strip);
  if (fit != TileFit::fits) return fit;
  tile.k0 = k0;
  tile.slices = k1 - k0 + 1;
  address_tile(w.local, w.strip.count, tile);
  return fit;
}

// Chunk [k0, k1] of a strip through tiles: one, or where its box is too large for one (rays that
// drift across y and z about as far as they advance along x, in oblique views), its first half
// and then the rest, halving down to kMinTileSlices before the bundles march in the volume
// itself (gathers, and on the back projection a scatter across rows and planes; 12 % of the
// tile chunks of spherical views did, benchmarks/paired.py). f(k_lo, k_hi, fit,
// in_volume) for each part in slice order, its tile (or in_volume) ready; parts where no lane
// has a sample are skipped.
constexpr int kMinTileSlices = 4;
template <class DF, class F>
HWY_INLINE void for_each_tile(DF df, const RayTable& t, int axis, int k0, int k1, StripWorkspace& w, Tile& tile, F&& f) {
  for (int k_lo = k0; k_lo <= k1;) {
    int k_hi = k1;
    const Bundle* in_volume;
    TileFit fit = start_chunk(df, t, axis, k_lo, k_hi, w, tile, in_volume);
    while (fit == TileFit::too_large && k_hi - k_lo + 1 > kMinTileSlices) {
      k_hi = k_lo + (k_hi - k_lo + 1) / 2 - 1;
      fit = start_chunk(df, t, axis, k_lo, k_hi, w, tile, in_volume);
    }
    if (fit != TileFit::nothing) f(k_lo, k_hi, fit, in_volume);
    k_lo = k_hi + 1;
  }
}

template <class DF>
HWY_INLINE void forward_strip(DF df, const RayTable& t, const float* HWY_RESTRICT volume, StripWorkspace& w,
                              float* HWY_RESTRICT out) {
  XStrip& s = w.strip;
  RayTable& local = w.local;
  prepare_strip(df, t, s, local);
  HWY_ALIGN float sums[XStrip::kMaxBundles * kMaxLanes];
  for (int i = 0; i < s.count; ++i) hn::Store(hn::Zero(df), df, sums + i * kMaxLanes);
  const XGrid g = x_grid(t, s, hn::Lanes(df));
  Tile tile;
  tile.data = w.tile_data.data();
  // A chunk's sums, carried from tile to tile when the chunk takes several (each lane then adds
  // its samples in the same order as through one tile). Summing straight into `sums` instead
  // saves this buffer and 0.5 % of instructions but measured 0.94 to 0.99 on circular views
  // (1.03 spherical; benchmarks/paired.py), so the buffer stays.
  HWY_ALIGN float chunk_sums[XStrip::kMaxBundles * kMaxLanes];
  TileDrift drift;
  for_each_chunk(s.k_lo, s.k_hi, 0, 1 << 30, [&](int k0, int k1) {
    for (int i = 0; i < s.count; ++i) hn::Store(hn::Zero(df), df, chunk_sums + i * kMaxLanes);
    const int next_k = next_chunk(k1, s.k_hi, 1 << 30);
    for_each_tile(df, t, -1, k0, k1, w, tile, [&](int k_lo, int k_hi, TileFit fit, const Bundle* in_volume) {
      if (fit == TileFit::fits) fill_tile(volume, g, tile, drift.next(next_k, tile));
      for (int i = 0; i < s.count; ++i) {
        const Bundle& b = in_volume ? in_volume[i] : s.tile[i];
        float* part = chunk_sums + i * kMaxLanes;
        const int first = std::max(k_lo, b.k_lo), last = std::min(k_hi, b.k_hi);
        hn::Store(in_volume ? march_forward(df, t, volume, b, first, last, hn::Load(df, part), Rows::fetch_ahead)
                            : march_forward(df, local, tile.data, b, first, last, hn::Load(df, part), Rows::cached),
                  df, part);
      }
    });
    for (int i = 0; i < s.count; ++i) {
      float* acc = sums + i * kMaxLanes;
      hn::Store(hn::Add(hn::Load(df, acc), hn::Load(df, chunk_sums + i * kMaxLanes)), df, acc);
    }
  });
  for (int i = 0; i < s.count; ++i) {
    const std::size_t r = s.entries[i];
    hn::StoreU(hn::Mul(hn::Load(df, sums + i * kMaxLanes), hn::LoadU(df, t.weight.data() + r)), df, out + r);
  }
}

template <class DF>
HWY_INLINE void back_strip(DF df, const RayTable& t, int k_begin, int k_end, StripWorkspace& w, float* HWY_RESTRICT volume) {
  XStrip& s = w.strip;
  RayTable& local = w.local;
  prepare_strip(df, t, s, local);
  const auto all = hn::FirstN(df, hn::Lanes(df));
  const XGrid g = x_grid(t, s, hn::Lanes(df));
  Tile tile;
  tile.data = w.tile_data.data();
  for_each_chunk(s.k_lo, s.k_hi, k_begin, k_end, [&](int k0, int k1) {
    const int next_k = next_chunk(k1, s.k_hi, k_end);  // the next slab's lines are another thread's
    for_each_tile(df, t, 0, k0, k1, w, tile, [&](int k_lo, int k_hi, TileFit fit, const Bundle* in_volume) {
      if (fit == TileFit::fits) std::fill_n(tile.data, tile.row(tile.slices, 0), 0.0f);
      for (int i = 0; i < s.count; ++i) {
        const std::size_t r = s.entries[i];
        const auto value = hn::Mul(hn::LoadU(df, t.value.data() + r), hn::LoadU(df, t.weight.data() + r));
        if (!in_volume) {
          const Bundle& b = s.tile[i];
          march_back(df, local, b, value, all, std::max(k_lo, b.k_lo), std::min(k_hi, b.k_hi), tile.data, Rows::cached);
        } else {
          const Bundle& b = in_volume[i];
          const auto on_axis = hn::RebindMask(
              df, hn::Eq(hn::LoadU(hn::RebindToSigned<DF>(), t.axis.data() + r), hn::Zero(hn::RebindToSigned<DF>())));
          march_back(df, t, b, value, on_axis, std::max(k_lo, b.k_lo), std::min(k_hi, b.k_hi), volume, Rows::fetch_ahead);
        }
      }
      if (fit == TileFit::fits) add_tile(tile, g, volume, NextChunk{next_k});  // no drift: 0.98-1.00
    });
  });
}

// Every bundle of the table. With `tiles`, the bundles along x of each strip (kStripColumns
// bundles of every row) are collected in w.strip and handed to `strip` together, after the
// others; those go to `one` in groups of kGroupColumns bundles of every row, the order in which
// neighbouring lines share rows of the volume (kForwardChunkSlices). Strips are twice as wide as
// the groups, so fewer voxels are copied into tiles (views mostly along x 1.1x faster); walking
// the other bundles in groups that wide made views along y and z 6 % slower (benchmarks/paired.py).
// runs_along_x(r) says whether the bundle at entry r goes along x (along_x).
constexpr int kGroupColumns = 4;
template <class DF, class AlongX, class One, class Strip>
HWY_INLINE void for_each_bundle(DF df, const RayTable& t, bool tiles, AlongX&& runs_along_x, StripWorkspace& w, One&& one,
                                Strip&& strip) {
  const int lanes = static_cast<int>(hn::Lanes(df));
  for (int slot = 0; slot < t.views; ++slot) {
    const int rows = t.rows_in(slot);
    // f(r) for the entries of `columns` bundles from column col0, row by row.
    const auto group = [&](int col0, int columns, auto&& f) {
      for (int row = 0; row < rows; ++row)
        for (int col = col0; col < std::min(t.row_stride, col0 + columns * lanes); col += lanes) f(t.entry(slot, row, col));
    };
    for (int col0 = 0; col0 < t.row_stride; col0 += kGroupColumns * lanes)
      group(col0, kGroupColumns, [&](std::size_t r) {
        if (!tiles || !runs_along_x(r)) one(r);
      });
    if (!tiles) continue;
    for (int col0 = 0; col0 < t.row_stride; col0 += kStripColumns * lanes) {
      w.strip.count = 0;
      group(col0, kStripColumns, [&](std::size_t r) {
        if (!runs_along_x(r)) return;
        if (w.strip.count < XStrip::kMaxBundles)
          w.strip.entries[w.strip.count++] = r;
        else
          one(r);
      });
      if (w.strip.count > 0) strip();
    }
  }
}

// Rays along x go strip by strip through tiles (above); the others chunk by chunk through the
// volume (kForwardChunkSlices), once every strip has been through.
void ForwardRays(const RayTable& t, const float* HWY_RESTRICT volume, float* HWY_RESTRICT out) {
  const hn::ScalableTag<float> df;
  const int N = static_cast<int>(hn::Lanes(df));
  static thread_local StripWorkspace w;
  w.reserve(t.rows, N);
  std::vector<Bundle> in_volume;
  std::vector<float> sums;
  // The bundles in `in_volume`, chunk by chunk, their sums times the path length into `out`.
  // (Equivalent forms, summing in `out` or zeroing with assign(), compiled to 4-8 % more
  // instructions and ran up to 20 % slower on the Zen 3: check with callgrind before reshaping.)
  const auto march_chunks = [&] {
    if (sums.size() < in_volume.size() * kMaxLanes) sums.resize(in_volume.size() * kMaxLanes);
    int lo = 1 << 30, hi = -(1 << 30);
    for (std::size_t i = 0; i < in_volume.size(); ++i) {
      lo = std::min(lo, in_volume[i].k_lo);
      hi = std::max(hi, in_volume[i].k_hi);
      hn::StoreU(hn::Zero(df), df, sums.data() + i * kMaxLanes);
    }
    for (int k0 = lo; k0 <= hi; k0 += kForwardChunkSlices) {
      const int k1 = std::min(hi, k0 + kForwardChunkSlices - 1);
      for (std::size_t i = 0; i < in_volume.size(); ++i) {
        const Bundle& b = in_volume[i];
        const int first = std::max(k0, b.k_lo), last = std::min(k1, b.k_hi);
        if (first > last) continue;
        float* acc = sums.data() + i * kMaxLanes;
        hn::StoreU(hn::Add(hn::LoadU(df, acc), march_forward(df, t, volume, b, first, last, hn::Zero(df), Rows::fetch_ahead)), df,
                   acc);
      }
    }
    for (std::size_t i = 0; i < in_volume.size(); ++i)
      hn::StoreU(hn::Mul(hn::LoadU(df, sums.data() + i * kMaxLanes), hn::LoadU(df, t.weight.data() + in_volume[i].r)), df,
                 out + in_volume[i].r);
  };
  for_each_bundle(
      df, t, true, [&](std::size_t r) { return along_x(df, t, r); }, w,
      [&](std::size_t r) {
        const Bundle b = bundle_at(t, r, static_cast<std::size_t>(N), -1);
        if (b.axis == 1 || b.axis == 2) {
          in_volume.push_back(b);
          return;
        }
        hn::StoreU(hn::Mul(march_forward(df, t, volume, b, b.k_lo, b.k_hi, hn::Zero(df), Rows::fetch_ahead),
                           hn::LoadU(df, t.weight.data() + r)),
                   df, out + r);
      },
      [&] { forward_strip(df, t, volume, w, out); });
  march_chunks();
}

// What BackRays keeps from call to call, each thread its own.
struct BackWorkspace {
  StripWorkspace strips;
  std::vector<Bundle> in_volume;  // bundles along y or z, every lane on the axis
  std::vector<Bundle> along_x;    // the strips' bundles, in the table's order (kBands)
#if HWY_TARGET != HWY_SCALAR
  BundleGroups groups;  // bundles by the part of the volume they cross
#endif
  std::vector<Bundle> left;      // bundles along x whose strips of columns did not pay
  std::vector<QuadBand> chunks;  // one group's bands, chunk by chunk
  std::vector<float> band_floats;
};

// Whether this target has bands (joseph_bands-inl.h): a quad is a 128-bit vector.
constexpr bool kBands = HWY_TARGET != HWY_SCALAR;
// Rows that bundles along y or z share a band by, where the table's band would not pay: the
// standard problem's spherical back projection 1.02-1.04x faster with 16 to 48 rows (8 rows
// 1.04x, 12 1.03x; in-process, benchmarks/paired.py).
constexpr float kBandRows = 32.0f;
#if HWY_TARGET != HWY_SCALAR
// Bundles along x of the slab [k_begin, k_end), through bands: groups of bundles of every view
// of the table that cross about the same voxels (so that a band gathers many samples per voxel),
// chunk by chunk of kTileSlices slices, each band added back through add_tile's transposition.
// The groups are first the table's strips of columns, which neighbouring views of a circular scan
// see the same part of the volume through; where those would not pay (in spherical views one
// column is another y in each view), the bundles whose middle lanes cross the same stretch of y,
// as wide as a strip, at the slab's middle. That second grouping alone made the spherical back
// projection 1.08x faster and the circular one 1.05x slower (its bands are a bundle wider). The
// bundles of groups that still would not pay in some chunk (BandFit::no: a few at the volume's
// edges, mostly) go strip by strip as before, view by view.
template <class DF>
HWY_INLINE void back_along_x_in_bands(DF df, const RayTable& t, int k_begin, int k_end, BackWorkspace& w,
                                      float* HWY_RESTRICT volume) {
  const std::size_t N = hn::Lanes(df);
  const std::size_t view_stride = static_cast<std::size_t>(t.view_stride), row_stride = static_cast<std::size_t>(t.row_stride);
  const std::size_t strip_width = kStripColumns * N;
  // Through bands if every chunk's pays; whether they did.
  const auto in_bands = [&](const Bundle* members, std::size_t count) {
    int k_lo = 1 << 30, k_hi = -(1 << 30);
    for (std::size_t i = 0; i < count; ++i) {
      k_lo = std::min(k_lo, members[i].k_lo);
      k_hi = std::max(k_hi, members[i].k_hi);
    }
    w.chunks.clear();
    bool pays = true;
    for_each_chunk(k_lo, k_hi, k_begin, k_end, [&](int k0, int k1) {
      QuadBand band;
      const BandFit fit = pays ? band_box(df, t, members, count, k0, k1, band) : BandFit::no;
      pays = pays && fit != BandFit::no;
      if (fit == BandFit::fits) w.chunks.push_back(band);
    });
    if (!pays) return false;
    const XGrid g = x_grid(t, members[0].r, N);
    for (QuadBand& band : w.chunks) {
      scatter_into_band(df, t, members, count, band, w.band_floats);
      add_tile(BandAlongX(band), g, volume, NextChunk{next_chunk(band.k0 + band.slices - 1, k_hi, k_end)});
    }
    return true;
  };
  w.left.clear();
  w.groups.sort(w.along_x.data(), w.along_x.size(),
                [&](const Bundle& b) { return static_cast<int>(b.r % view_stride % row_stride / strip_width); });
  w.groups.for_each([&](const Bundle* members, std::size_t count) {
    if (!in_bands(members, count)) w.left.insert(w.left.end(), members, members + count);
  });
  const float k_middle = 0.5f * static_cast<float>(k_begin + k_end - 1);
  w.groups.sort(w.left.data(), w.left.size(),
                [&](const Bundle& b) { return stretch_of(t, b, N, k_middle, false, static_cast<float>(strip_width)); });
  w.groups.for_each([&](const Bundle* members, std::size_t count) {
    if (in_bands(members, count)) return;
    // Strip by strip: a view's bundles of the group, as many as the strip's copies hold.
    const int most = w.strips.local.rows;
    for (std::size_t i = 0; i < count;) {
      const std::size_t view = members[i].r / view_stride;
      XStrip& s = w.strips.strip;
      s.count = 0;
      for (; i < count && members[i].r / view_stride == view && s.count < most; ++i) s.entries[s.count++] = members[i].r;
      back_strip(df, t, k_begin, k_end, w.strips, volume);
    }
  });
}
#endif

// NOLINTNEXTLINE(readability-function-size): its stages share the thread's workspace and the scatter in flight
void BackRays(const RayTable& t, int axis, int k_begin, int k_end, float* HWY_RESTRICT volume) {
  const hn::ScalableTag<float> df;
  const hn::RebindToSigned<decltype(df)> di;
  const int N = static_cast<int>(hn::Lanes(df));
  static thread_local BackWorkspace w;
  if (axis == 0) w.strips.reserve(t.rows, N);
  w.in_volume.clear();
  w.along_x.clear();
  std::vector<Bundle>& in_volume = w.in_volume;
  // along_x from the bundles the fillers prepared (RayTable::bundles), without loading the lanes'
  // axes and ranges for the many bundles whose lanes share one axis: walking the table in every
  // slab task took 5-9 % of a spherical back projection (benchmarks/paired.py).
  const auto runs_along_x = [&](std::size_t r) {
    const Bundle& b = t.bundles[r / static_cast<std::size_t>(N)];
    return b.axis == -2 ? along_x(df, t, r) : b.axis == 0 && b.k_lo <= b.k_hi;
  };
  // Bundles along x have lanes on axis 0 only, so only axis 0's slabs take strips.
  for_each_bundle(
      df, t, axis == 0, runs_along_x, w.strips,
      [&](std::size_t r) {
        const Bundle& prepared = t.bundles[r / static_cast<std::size_t>(N)];
        if (prepared.axis != -2 && prepared.axis != axis) return;  // another axis's slabs take it
        if (prepared.axis == axis && axis != 0) {
          if (std::max(prepared.k_lo, k_begin) <= std::min(prepared.k_hi, k_end - 1)) in_volume.push_back(prepared);
          return;
        }
        // Lanes of several axes, or along x past a strip's room: marched here.
        const auto on_axis = hn::RebindMask(df, hn::Eq(hn::LoadU(di, t.axis.data() + r), hn::Set(di, axis)));
        if (hn::AllFalse(df, on_axis)) return;
        const Bundle b = table_bundle(t, r, static_cast<std::size_t>(N), axis);
        const auto value = hn::Mul(hn::LoadU(df, t.value.data() + r), hn::LoadU(df, t.weight.data() + r));
        march_back(df, t, b, value, on_axis, std::max(b.k_lo, k_begin), std::min(b.k_hi, k_end - 1), volume, Rows::fetch_ahead);
      },
      [&] {
        if (!kBands) {
          back_strip(df, t, k_begin, k_end, w.strips, volume);
          return;
        }
        // Kept for back_along_x_in_bands.
        const XStrip& s = w.strips.strip;
        for (int i = 0; i < s.count; ++i) {
          const Bundle b = table_bundle(t, s.entries[i], static_cast<std::size_t>(N), -1);
          if (std::max(b.k_lo, k_begin) <= std::min(b.k_hi, k_end - 1)) w.along_x.push_back(b);
        }
      });
#if HWY_TARGET != HWY_SCALAR
  if (axis == 0) back_along_x_in_bands(df, t, k_begin, k_end, w, volume);
#endif
  const auto all = hn::FirstN(df, hn::Lanes(df));
  // A bundle's interior chunk is added only after the next bundle's corners are found and its
  // rows asked for: those rows then have a bundle's additions to arrive instead of none (the
  // first rows of a chunk had been asked for right before their loads). Each voxel still
  // receives the bundles in order. Spherical 1.02-1.035x, circular 0.97-1.01x (benchmarks/paired.py);
  // asking two or three bundles ahead gained nothing more.
  static_assert(kBackChunkSlices <= kInteriorBatch, "a bundle's chunk is one batch");
  InteriorScatter<hn::ScalableTag<float>> scatter[2];
  int pending = -1;  // the scatter found and not yet added, if any
  const auto add_pending = [&] {
    if (pending >= 0) scatter[pending].add(df, volume);
    pending = -1;
  };
  // The samples of bundles[0, count) in slices [k0, k1] straight into the volume.
  const auto scatter_into_volume = [&](const Bundle* bundles, std::size_t count, int k0, int k1) {
    for (std::size_t i = 0; i < count; ++i) {
      const Bundle& b = bundles[i];
      const int first = std::max(k0, b.k_lo), last = std::min(k1, b.k_hi);
      if (first > last) continue;
      const auto value = hn::Mul(hn::LoadU(df, t.value.data() + b.r), hn::LoadU(df, t.weight.data() + b.r));
      if (first < b.in_lo || last > b.in_hi) {  // masked slices: march_back, in order
        add_pending();
        march_back(df, t, b, value, all, first, last, volume, Rows::fetch_ahead);
        continue;
      }
      const int next = pending == 0 ? 1 : 0;
      scatter[next].corners(df, t, b.r, first, last - first + 1, value, volume, Rows::fetch_ahead);
      add_pending();
      pending = next;
    }
  };
  for (int k0 = k_begin; k0 < k_end; k0 += kBackChunkSlices) {
    const int k1 = std::min(k_end - 1, k0 + kBackChunkSlices - 1);
#if HWY_TARGET != HWY_SCALAR
    // The bundles through one band where it pays, their samples added to the volume band by band.
    const auto through_band = [&](const Bundle* bundles, std::size_t count) {
      QuadBand band;
      const BandFit fit = band_box(df, t, bundles, count, k0, k1, band);
      if (fit == BandFit::fits) {
        add_pending();
        const std::size_t r = bundles[0].r;
        scatter_into_band(df, t, bundles, count, band, w.band_floats);
        add_band(df, band, t.stride_a[r], t.stride_c[r], t.n_b[r], t.n_c[r], volume);
      }
      return fit;
    };
    // Every bundle of the chunk through one band: in circular views the table's views (16 in the
    // standard problem) share their band of rows, and it gathers about ten samples per voxel.
    // Where that band would not pay (spherical views, whose lines part away from the volume's
    // centre), the bundles that cross the same kBandRows rows at the chunk's middle share one,
    // and those left over scatter into the volume.
    const BandFit fit = in_volume.empty() ? BandFit::nothing : through_band(in_volume.data(), in_volume.size());
    if (fit == BandFit::nothing || fit == BandFit::fits) continue;
    const float k_middle = 0.5f * static_cast<float>(k0 + k1);
    w.groups.sort(in_volume.data(), in_volume.size(),
                  [&](const Bundle& b) { return stretch_of(t, b, hn::Lanes(df), k_middle, true, kBandRows); });
    w.groups.for_each([&](const Bundle* members, std::size_t count) {
      if (through_band(members, count) == BandFit::no) scatter_into_volume(members, count, k0, k1);
    });
#else
    scatter_into_volume(in_volume.data(), in_volume.size(), k0, k1);
#endif
  }
  add_pending();
}

// Every lane on one axis (the usual case): the bundle restricted to that axis is the bundle.
// Only bundles of rows in use: rows past a slot's (RayTable::slot_rows) hold stale rays, and the
// callers (the fillers of their rays) pass none of them.
void PrepareBundles(RayTable& t, std::size_t begin, std::size_t end) {
  const std::size_t n = hn::Lanes(hn::ScalableTag<float>());
  for (std::size_t i = begin; i < end; ++i) t.bundles[i] = bundle_at(t, i * n, n, -1);
}

const char* TargetName() { return hwy::TargetName(HWY_TARGET); }
int FloatLanes() { return static_cast<int>(hn::Lanes(hn::ScalableTag<float>())); }

}  // namespace HWY_NAMESPACE
}  // namespace ctk::detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace ctk::detail {
HWY_EXPORT(ForwardRays);
HWY_EXPORT(BackRays);
HWY_EXPORT(PrepareBundles);
HWY_EXPORT(TargetName);
HWY_EXPORT(FloatLanes);

void forward_rays(const RayTable& t, const float* volume, float* out) { HWY_DYNAMIC_DISPATCH(ForwardRays)(t, volume, out); }
void back_rays(const RayTable& t, int axis, int k_begin, int k_end, float* volume) {
  HWY_DYNAMIC_DISPATCH(BackRays)(t, axis, k_begin, k_end, volume);
}
void prepare_bundles(RayTable& t, std::size_t begin, std::size_t end) { HWY_DYNAMIC_DISPATCH(PrepareBundles)(t, begin, end); }
std::size_t bundle_count(const RayTable& t) {
  return static_cast<std::size_t>(t.views) * static_cast<std::size_t>(t.view_stride) /
         static_cast<std::size_t>(simd_float_lanes());
}
const char* simd_target_name() { return HWY_DYNAMIC_DISPATCH(TargetName)(); }
int simd_float_lanes() { return HWY_DYNAMIC_DISPATCH(FloatLanes)(); }
}  // namespace ctk::detail
#endif
