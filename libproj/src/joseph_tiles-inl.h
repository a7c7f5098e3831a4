// Per SIMD target: tiles for rays along x. The volume's contiguous axis is x, so rays marching
// along it find their neighbours' corners a row or a plane away; a tile is a small transposed
// copy of 16 slices in which they march like rays along y.
#if defined(CTK_PROJ_JOSEPH_TILES_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef CTK_PROJ_JOSEPH_TILES_INL_H_
#undef CTK_PROJ_JOSEPH_TILES_INL_H_
#else
#define CTK_PROJ_JOSEPH_TILES_INL_H_
#endif

#include <hwy/highway.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>

#include "joseph_samples-inl.h"
#include "ray_table.hpp"

HWY_BEFORE_NAMESPACE();
namespace ctk::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// Rays along x step across the volume's contiguous axis: neighbouring rays' corners are a row
// (y) or a plane (z) apart and have to be gathered one by one. So the bundles of one column
// strip of a table (one per detector row) are marched through a tile instead: the slices of 16
// steps, copied with y contiguous (a transposition), where the row-window paths apply as they
// do to rays along y and z. Voxels outside the volume are zeros in the tile, as the masked
// paths make them. A tile is at most kTileSlices (ray_table.hpp) x kTileMaxHeight x
// kTileMaxWidth floats (384 kB).
// Bundles of this many neighbouring columns (and every row of the table) share a tile: 64
// pixels of a line, whatever the lanes. Wider tiles copy each voxel fewer times (a tile's width
// is its lanes' span plus the rays' drift): 64 pixels rather than 32 on AVX2
// (spherical views 1.04x each way, benchmarks/paired.py). But 128 pixels span about 137 voxels in the standard
// problem, more than kTileMaxWidth: with 8 bundles of 16 lanes, AVX-512 sent nearly every ray
// along x to the gathers (64 pixels made the Zen 4's circular forward 1.4x
// and back 1.28x faster, 96 pixels or 256-voxel tiles less so).
constexpr int kStripColumns = 64 / static_cast<int>(HWY_LANES(float));
// Tables of 24 lines (JosephProjector::default_rows_per_block, spherical views) span about 26
// rows along z plus the drift of oblique rays: 48 rather than 24 (benchmarks/paired.py).
constexpr int kTileMaxWidth = 128, kTileMaxHeight = 48;

struct Tile {
  int k0 = 0, slices = 0;  // x range k0 .. k0 + slices - 1
  int y0 = 0, width = 0;   // y range, contiguous; a multiple of 16 and at least 32
  int z0 = 0, height = 0;  // z range
  float* data = nullptr;   // [slice][z][y]
  std::size_t row(int kk, int zz) const {
    return (static_cast<std::size_t>(kk) * static_cast<std::size_t>(height) + static_cast<std::size_t>(zz)) *
           static_cast<std::size_t>(width);
  }
  // Voxels yy .. yy + Lanes(d) - 1 of row zz of slice kk (tile coordinates), and one voxel, as
  // add_tile reads them (so that it reads a band the same way, joseph_bands-inl.h).
  template <class D>
  HWY_INLINE hn::Vec<D> load(D d, int kk, int zz, int yy) const {
    return hn::LoadU(d, data + row(kk, zz) + yy);
  }
  float at(int kk, int zz, int yy) const { return data[row(kk, zz) + static_cast<std::size_t>(yy)]; }
};

// Where the volume's voxels are for rays along x (their b is y, their c is z).
struct XGrid {
  std::ptrdiff_t stride_y = 0, stride_z = 0;
  int ny = 0, nz = 0;
};

#if HWY_TARGET <= HWY_AVX3
// In place: row j of the input becomes column j.
HWY_INLINE void transpose16(__m512 (&r)[16]) {
  __m512 t[16];
  for (int i = 0; i < 8; ++i) {
    t[2 * i] = _mm512_unpacklo_ps(r[2 * i], r[2 * i + 1]);
    t[2 * i + 1] = _mm512_unpackhi_ps(r[2 * i], r[2 * i + 1]);
  }
  const auto lo64 = [](__m512 a, __m512 b) {
    return _mm512_castpd_ps(_mm512_unpacklo_pd(_mm512_castps_pd(a), _mm512_castps_pd(b)));
  };
  const auto hi64 = [](__m512 a, __m512 b) {
    return _mm512_castpd_ps(_mm512_unpackhi_pd(_mm512_castps_pd(a), _mm512_castps_pd(b)));
  };
  for (int i = 0; i < 4; ++i) {  // r[4i + j]: rows 4i .. 4i + 3 of column j of each 4-column block
    r[4 * i] = lo64(t[4 * i], t[4 * i + 2]);
    r[4 * i + 1] = hi64(t[4 * i], t[4 * i + 2]);
    r[4 * i + 2] = lo64(t[4 * i + 1], t[4 * i + 3]);
    r[4 * i + 3] = hi64(t[4 * i + 1], t[4 * i + 3]);
  }
  for (int i = 0; i < 4; ++i) {
    t[i] = _mm512_shuffle_f32x4(r[i], r[4 + i], 0x88);
    t[4 + i] = _mm512_shuffle_f32x4(r[i], r[4 + i], 0xdd);
    t[8 + i] = _mm512_shuffle_f32x4(r[8 + i], r[12 + i], 0x88);
    t[12 + i] = _mm512_shuffle_f32x4(r[8 + i], r[12 + i], 0xdd);
  }
  for (int i = 0; i < 4; ++i) {
    r[i] = _mm512_shuffle_f32x4(t[i], t[8 + i], 0x88);
    r[8 + i] = _mm512_shuffle_f32x4(t[i], t[8 + i], 0xdd);
    r[4 + i] = _mm512_shuffle_f32x4(t[4 + i], t[12 + i], 0x88);
    r[12 + i] = _mm512_shuffle_f32x4(t[4 + i], t[12 + i], 0xdd);
  }
}
#elif HWY_TARGET == HWY_AVX2
// In place: row j of the input becomes column j (8 x 8).
HWY_INLINE void transpose8(__m256 (&r)[8]) {
  __m256 t[8], s[8];
  for (int i = 0; i < 4; ++i) {
    t[2 * i] = _mm256_unpacklo_ps(r[2 * i], r[2 * i + 1]);
    t[2 * i + 1] = _mm256_unpackhi_ps(r[2 * i], r[2 * i + 1]);
  }
  for (int i = 0; i < 2; ++i) {  // s[4i + j]: rows 4i .. 4i + 3 of columns j and j + 4
    s[4 * i] = _mm256_shuffle_ps(t[4 * i], t[4 * i + 2], 0x44);
    s[4 * i + 1] = _mm256_shuffle_ps(t[4 * i], t[4 * i + 2], 0xEE);
    s[4 * i + 2] = _mm256_shuffle_ps(t[4 * i + 1], t[4 * i + 3], 0x44);
    s[4 * i + 3] = _mm256_shuffle_ps(t[4 * i + 1], t[4 * i + 3], 0xEE);
  }
  for (int j = 0; j < 4; ++j) {
    r[j] = _mm256_permute2f128_ps(s[j], s[4 + j], 0x20);
    r[4 + j] = _mm256_permute2f128_ps(s[j], s[4 + j], 0x31);
  }
}

// f(k8, n, lanes, yb) for each block of a tile row of 8 slices (k8 .. k8 + n - 1, n <= 8, and
// `lanes` the first n, the mask of AVX2's masked loads and stores) by 8 voxels along y (from yb).
template <class TileLike, class F>
HWY_INLINE void for_each_block8(const TileLike& tile, F&& f) {
  for (int k8 = 0; k8 < tile.slices; k8 += 8) {
    const int n = std::min(8, tile.slices - k8);
    const __m256i lanes = _mm256_cmpgt_epi32(_mm256_set1_epi32(n), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
    for (int yb = 0; yb < tile.width; yb += 8) f(k8, n, lanes, yb);
  }
}
#endif

// A tile is filled (forward) or added back (back projection), at each (y, z) of its box,
// through the volume's line of 16 floats along x that holds its slices (chunks are aligned to
// kTileSlices); the strip's next chunk takes the line after it. Asking for that line as each line
// is read gives it a whole chunk's march to arrive: in spherical views, which read the whole
// volume, the fill's loads waited on memory (in `perf`, the first load of each 16 x 16 block held
// 12 % of a strip's samples). Forward 1.09-1.12x spherical, 0.98-1.04x circular; back, with
// add_tile's unmasked whole lines, 1.04-1.05x on AVX-512 and 1.00-1.01x on AVX2 (Zen 5,
// benchmarks/paired.py). Asking for the next chunk's whole box at once, at its start, gained nothing: a burst of a
// thousand requests the current loads queued behind. The rays are straight, so the next chunk's
// box lies about as far on (in y and z) from this chunk's as this one's from the last: the line
// asked for is (y, z) moved by that much, not (y, z) itself (oblique spherical views drift by
// several rows a chunk; forward 1.06x spherical, 1.01x circular, benchmarks/paired.py). The back
// projection keeps (y, z) itself: its drift measured 0.98-1.00. Asking for the next box's own
// lines, found by tile_box and dealt out a share per row of this one, measured no better.
struct NextChunk {
  int k = -1;          // its first slice; negative where there is none, or (back projection) where
                       // it lies in the next slab, whose lines another thread writes (0.93 circular)
  int dy = 0, dz = 0;  // its box's expected offset from this chunk's
  // The address where the next chunk's lines for this chunk's row z start (the line for y is
  // y * stride_y floats on), or 0 where there are none. An integer: with the drift, it and the
  // lines from it may lie outside the array (below).
  HWY_INLINE std::uintptr_t row(const float* volume, const XGrid& g, int z) const {
    const int z_next = z + dz;
    if (k < 0 || z_next < 0 || z_next >= g.nz) return 0;
    const std::ptrdiff_t floats = k + dy * g.stride_y + z_next * g.stride_z;
    return reinterpret_cast<std::uintptr_t>(volume) +
           static_cast<std::uintptr_t>(floats * static_cast<std::ptrdiff_t>(sizeof(float)));
  }
  // Asks for the next chunk's line for this chunk's line at y of a row (next_row: row()). y + dy
  // is not tested: a line past the row is the next row's, and past the volume's first or last
  // plane a request that finds nothing (a prefetch never faults). Testing it cost as much as
  // the drift gained.
  HWY_INLINE void ask(std::uintptr_t next_row, const XGrid& g, int y) const {
    if (next_row == 0) return;
    const std::ptrdiff_t floats = static_cast<std::ptrdiff_t>(y) * g.stride_y;
    // The next row's address is kept as an integer (0: none).
    hwy::Prefetch(reinterpret_cast<const float*>(  // NOLINT(performance-no-int-to-ptr)
        next_row + static_cast<std::uintptr_t>(floats * static_cast<std::ptrdiff_t>(sizeof(float)))));
  }
};

// How a strip's tiles move from chunk to chunk, for NextChunk.
class TileDrift {
 public:
  // The next chunk (first slice next_k) of `tile`, whose box is now known.
  NextChunk next(int next_k, const Tile& tile) {
    NextChunk n;
    n.k = next_k;
    if (seen_ && tile.k0 > k0_) {  // scaled to a whole chunk: tiles of 8 or 4 slices move less
      n.dy = (tile.y0 - y0_) * kTileSlices / (tile.k0 - k0_);
      n.dz = (tile.z0 - z0_) * kTileSlices / (tile.k0 - k0_);
    }
    seen_ = true;
    k0_ = tile.k0, y0_ = tile.y0, z0_ = tile.z0;
    return n;
  }

 private:
  bool seen_ = false;
  int k0_ = 0, y0_ = 0, z0_ = 0;
};

// The same for every line of the tile's row z inside the volume (for the scalar copies below,
// which visit a line once per slice).
template <class TileLike>
HWY_INLINE void ask_for_next_lines(const float* volume, const XGrid& g, const TileLike& tile, int z, const NextChunk& next) {
  const std::uintptr_t next_row = next.row(volume, g, z);
  for (int yy = 0; yy < tile.width; ++yy) next.ask(next_row, g, tile.y0 + yy);
}

// The first slice of the next chunk after one ending at slice k1 of a strip whose slices end at
// k_hi, within slices [.., k_end) (the slab, back projection; unbounded, forward); -1 for none.
HWY_INLINE int next_chunk(int k1, int k_hi, int k_end) { return k1 < k_hi && k1 + kTileSlices < k_end ? k1 + 1 : -1; }

// tile = the volume in the tile's box (zero outside the volume), the lines of the strip's next
// chunk asked for (NextChunk). The tile and grid are taken by value: vector stores may
// alias anything, so fields read through a reference were reloaded after every store.
HWY_INLINE void fill_tile(const float* HWY_RESTRICT volume, const XGrid g, const Tile tile, const NextChunk next) {
  for (int zz = 0; zz < tile.height; ++zz) {
    const int z = tile.z0 + zz;
    const bool z_in = z >= 0 && z < g.nz;
    const std::uintptr_t next_row = next.row(volume, g, z);
#if HWY_TARGET <= HWY_AVX3
    const auto slices = static_cast<__mmask16>((1u << tile.slices) - 1u);
    for (int yb = 0; yb < tile.width; yb += 16) {
      __m512 r[16];
      for (int j = 0; j < 16; ++j) {
        const int y = tile.y0 + yb + j;
        if (!z_in || y < 0 || y >= g.ny) {
          r[j] = _mm512_setzero_ps();
          continue;
        }
        const std::ptrdiff_t at = y * g.stride_y + z * g.stride_z;
        r[j] = _mm512_maskz_loadu_ps(slices, volume + tile.k0 + at);
        next.ask(next_row, g, y);
      }
      transpose16(r);
      for (int kk = 0; kk < tile.slices; ++kk) _mm512_storeu_ps(tile.data + tile.row(kk, zz) + yb, r[kk]);
    }
#elif HWY_TARGET == HWY_AVX2
    // Blocks of 8 y by 8 slices; the scalar copy below read one float per stride_y and took half
    // of a strip's forward projection on a Zen 3.
    for_each_block8(tile, [&](int k8, int n, __m256i lanes, int yb) {
      __m256 r[8];
      const int y = tile.y0 + yb;
      const std::ptrdiff_t at = tile.k0 + k8 + y * g.stride_y + z * g.stride_z;  // row j at + j stride_y, if inside
      if (z_in && n == 8 && y >= 0 && y + 8 <= g.ny) {                           // the usual block: whole and inside
        for (int j = 0; j < 8; ++j) {
          r[j] = _mm256_loadu_ps(volume + at + j * g.stride_y);
          if (k8 == 0) next.ask(next_row, g, y + j);
        }
      } else {
        for (int j = 0; j < 8; ++j) {
          const bool inside = z_in && y + j >= 0 && y + j < g.ny;
          const float* v = inside ? volume + at + j * g.stride_y : volume;
          r[j] = !inside ? _mm256_setzero_ps() : n == 8 ? _mm256_loadu_ps(v) : _mm256_maskload_ps(v, lanes);
        }
      }
      transpose8(r);
      for (int kk = 0; kk < n; ++kk) _mm256_storeu_ps(tile.data + tile.row(k8 + kk, zz) + yb, r[kk]);
    });
#else
    if (z_in) ask_for_next_lines(volume, g, tile, z, next);
    for (int kk = 0; kk < tile.slices; ++kk)
      for (int yy = 0; yy < tile.width; ++yy) {
        const int y = tile.y0 + yy;
        tile.data[tile.row(kk, zz) + static_cast<std::size_t>(yy)] =
            z_in && y >= 0 && y < g.ny ? volume[tile.k0 + kk + y * g.stride_y + z * g.stride_z] : 0.0f;
      }
#endif
  }
}

// volume += tile, inside the volume, the lines of the strip's next chunk asked for
// (NextChunk; by value, as fill_tile). TileLike: a Tile, or anything with its box (k0, slices,
// y0, width, z0, height) and its load() and at().
template <class TileLike>
HWY_INLINE void add_tile(const TileLike tile, const XGrid g, float* HWY_RESTRICT volume, const NextChunk next) {
  for (int zz = 0; zz < tile.height; ++zz) {
    const int z = tile.z0 + zz;
    if (z < 0 || z >= g.nz) continue;
    const std::uintptr_t next_row = next.row(volume, g, z);
#if HWY_TARGET <= HWY_AVX3
    const auto slices = static_cast<__mmask16>((1u << tile.slices) - 1u);
    for (int yb = 0; yb < tile.width; yb += 16) {
      __m512 r[16];
      for (int kk = 0; kk < 16; ++kk)
        r[kk] = kk < tile.slices ? tile.load(hn::Full512<float>(), kk, zz, yb).raw : _mm512_setzero_ps();
      transpose16(r);
      for (int j = 0; j < 16; ++j) {
        const int y = tile.y0 + yb + j;
        if (y < 0 || y >= g.ny) continue;
        const std::ptrdiff_t at = y * g.stride_y + z * g.stride_z;
        float* v = volume + tile.k0 + at;
        if (tile.slices == kTileSlices)  // a whole line: unmasked, 1.03x of the back projection alone
          _mm512_storeu_ps(v, _mm512_add_ps(_mm512_loadu_ps(v), r[j]));
        else
          _mm512_mask_storeu_ps(v, slices, _mm512_add_ps(_mm512_maskz_loadu_ps(slices, v), r[j]));
        next.ask(next_row, g, y);
      }
    }
#elif HWY_TARGET == HWY_AVX2
    for_each_block8(tile, [&](int k8, int n, __m256i lanes, int yb) {
      __m256 r[8];
      for (int kk = 0; kk < 8; ++kk) r[kk] = kk < n ? tile.load(hn::Full256<float>(), k8 + kk, zz, yb).raw : _mm256_setzero_ps();
      transpose8(r);
      const int y = tile.y0 + yb;
      const std::ptrdiff_t at = tile.k0 + k8 + y * g.stride_y + z * g.stride_z;  // row j at + j stride_y, if inside
      if (n == 8 && y >= 0 && y + 8 <= g.ny) {                                   // the usual block: whole and inside
        for (int j = 0; j < 8; ++j) {
          float* v = volume + at + j * g.stride_y;
          _mm256_storeu_ps(v, _mm256_add_ps(_mm256_loadu_ps(v), r[j]));
          if (k8 == 0) next.ask(next_row, g, y + j);
        }
        return;
      }
      for (int j = 0; j < 8; ++j) {
        if (y + j < 0 || y + j >= g.ny) continue;
        float* v = volume + at + j * g.stride_y;
        if (n == 8)
          _mm256_storeu_ps(v, _mm256_add_ps(_mm256_loadu_ps(v), r[j]));
        else
          _mm256_maskstore_ps(v, lanes, _mm256_add_ps(_mm256_maskload_ps(v, lanes), r[j]));
      }
    });
#else
    for (int kk = 0; kk < tile.slices; ++kk)
      for (int yy = 0; yy < tile.width; ++yy) {
        const int y = tile.y0 + yy;
        if (y >= 0 && y < g.ny) volume[tile.k0 + kk + y * g.stride_y + z * g.stride_z] += tile.at(kk, zz, yy);
      }
    ask_for_next_lines(volume, g, tile, z, next);
#endif
  }
}

// A bundle whose rays (those that meet the volume, at least one) all run along x. (As a loop
// over lanes this was 1.8 % of a circular back projection: every slab task asks it of every
// bundle, twice.)
template <class DF>
HWY_INLINE bool along_x(DF, const RayTable& t, std::size_t r) {
  const hn::RebindToSigned<DF> di;
  const auto meets = hn::Not(hn::Lt(hn::LoadU(di, t.k_last.data() + r), hn::LoadU(di, t.k_first.data() + r)));
  const auto other_axis = hn::Not(hn::Eq(hn::LoadU(di, t.axis.data() + r), hn::Zero(di)));
  return !hn::AllFalse(di, meets) && hn::AllFalse(di, hn::And(meets, other_axis));
}

enum class TileFit { nothing, fits, too_large };

// The box of voxels (corners included) that the samples of bundles in slices [k0, k1] touch, lane
// by lane within each lane's own range; grown bundle by bundle (add). For tiles (tile_box) and the
// back projection's bands (band_box, joseph_bands-inl.h).
template <class DF>
class SampleBox {
 public:
  explicit SampleBox(DF) : lo_b_(hn::Set(DI(), kFar)), hi_b_(hn::Set(DI(), -kFar)), lo_c_(lo_b_), hi_c_(hi_b_) {}
  void add(DF df, const RayTable& t, std::size_t r, int k0, int k1) {
    const DI di;
    const auto ka = hn::Max(hn::LoadU(di, t.k_first.data() + r), hn::Set(di, k0));
    const auto kb = hn::Min(hn::LoadU(di, t.k_last.data() + r), hn::Set(di, k1));
    const auto valid = hn::Lt(ka, hn::Add(kb, hn::Set(di, 1)));
    // The sample moves linearly with k: its ends bound it. Same arithmetic as the kernels.
    const BundlePosition<DF> position(df, t, r);
    const auto pa = position.at(df, hn::ConvertTo(df, ka)), pb = position.at(df, hn::ConvertTo(df, kb));
    lo_b_ = hn::IfThenElse(valid, hn::Min(lo_b_, hn::Min(pa.ib, pb.ib)), lo_b_);
    hi_b_ = hn::IfThenElse(valid, hn::Max(hi_b_, hn::Max(pa.ib, pb.ib)), hi_b_);
    lo_c_ = hn::IfThenElse(valid, hn::Min(lo_c_, hn::Min(pa.ic, pb.ic)), lo_c_);
    hi_c_ = hn::IfThenElse(valid, hn::Max(hi_c_, hn::Max(pa.ic, pb.ic)), hi_c_);
  }
  // The lower corners' range (the box reaches one voxel further); b_hi() < b_lo() while empty.
  int b_lo() const { return hn::GetLane(hn::MinOfLanes(DI(), lo_b_)); }
  int b_hi() const { return hn::GetLane(hn::MaxOfLanes(DI(), hi_b_)); }
  int c_lo() const { return hn::GetLane(hn::MinOfLanes(DI(), lo_c_)); }
  int c_hi() const { return hn::GetLane(hn::MaxOfLanes(DI(), hi_c_)); }

 private:
  using DI = hn::RebindToSigned<DF>;
  static constexpr int kFar = 1 << 30;
  hn::Vec<DI> lo_b_, hi_b_, lo_c_, hi_c_;
};

// The box of voxels (corners included) the lanes at entries[0 .. count) of `t` touch in slices
// [k0, k1], as the tile's y and z ranges; nothing when no lane has a sample there.
template <class DF>
HWY_INLINE TileFit tile_box(DF df, const RayTable& t, const std::size_t* entries, int count, int k0, int k1, Tile& tile) {
  SampleBox<DF> box(df);
  for (int i = 0; i < count; ++i) box.add(df, t, entries[i], k0, k1);
  const int y0 = box.b_lo(), y1 = box.b_hi() + 1;
  if (y1 < y0) return TileFit::nothing;
  tile.y0 = y0;
  tile.width = std::max(32, (y1 - y0 + 16) / 16 * 16);
  tile.z0 = box.c_lo();
  tile.height = box.c_hi() + 2 - tile.z0;
  return tile.width <= kTileMaxWidth && tile.height <= kTileMaxHeight ? TileFit::fits : TileFit::too_large;
}

// The copies of a strip's bundles (in `local`, one row each) address the tile.
HWY_INLINE void address_tile(RayTable& local, int count, const Tile& tile) {
  local.origin_a = tile.k0;
  local.origin_b = tile.y0;
  local.origin_c = tile.z0;
  const std::size_t n = static_cast<std::size_t>(count) * static_cast<std::size_t>(local.row_stride);
  std::fill_n(local.stride_a.begin(), n, tile.width * tile.height);
  std::fill_n(local.stride_b.begin(), n, 1);
  std::fill_n(local.stride_c.begin(), n, tile.width);
  std::fill_n(local.n_b.begin(), n, tile.width);
  std::fill_n(local.n_c.begin(), n, tile.height);
}

}  // namespace HWY_NAMESPACE
}  // namespace ctk::detail
HWY_AFTER_NAMESPACE();

#endif
