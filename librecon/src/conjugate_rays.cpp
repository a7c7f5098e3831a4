#include "ctk/recon/conjugate_rays.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "ctk/core/statistics.hpp"

namespace ctk {

namespace {

constexpr int kBlocks = 16;  // jackknife blocks of consecutive views

// Squared mismatch and pair count, per block of views, for one u0 and sense.
struct Mismatch {
  std::vector<double> sum = std::vector<double>(kBlocks, 0.0);
  std::vector<std::int64_t> count = std::vector<std::int64_t>(kBlocks, 0);
  double total() const {
    double s = 0;
    std::int64_t n = 0;
    for (int b = 0; b < kBlocks; ++b) {
      s += sum[static_cast<std::size_t>(b)];
      n += count[static_cast<std::size_t>(b)];
    }
    return n > 0 ? s / static_cast<double>(n) : std::numeric_limits<double>::infinity();
  }
  // Over the blocks of one pair of opposite quarter turns (`part` 0: the first and third quarters,
  // 1: the second and fourth): a pair of conjugate views lies in one part, so the two parts
  // share no measurement.
  double in_quarters(int part) const {
    double s = 0;
    std::int64_t n = 0;
    for (int b = 0; b < kBlocks; ++b)
      if ((b * 4 / kBlocks) % 2 == part) {
        s += sum[static_cast<std::size_t>(b)];
        n += count[static_cast<std::size_t>(b)];
      }
    return n > 0 ? s / static_cast<double>(n) : std::numeric_limits<double>::infinity();
  }
  double without(int block) const {
    double s = 0;
    std::int64_t n = 0;
    for (int b = 0; b < kBlocks; ++b)
      if (b != block) {
        s += sum[static_cast<std::size_t>(b)];
        n += count[static_cast<std::size_t>(b)];
      }
    return n > 0 ? s / static_cast<double>(n) : std::numeric_limits<double>::infinity();
  }
};

// Every `stride`-th view is compared with its conjugates (the coarse search needs no more).
Mismatch mismatch(const FanSinogram& s, int period, double u0, int sense, int stride = 1) {
  const double step = std::abs(s.step_rad), scale = s.pitch_mm / s.source_to_detector_mm;
  Mismatch m;
  // Per column, where its conjugate lies: how many views on, and which column.
  std::vector<int> columns;
  std::vector<double> views_on;
  for (int u = 0; u < s.cols; ++u) {
    const double mirrored = 2 * u0 - u;
    if (mirrored < 0 || mirrored > s.cols - 1) continue;
    columns.push_back(u);
    views_on.push_back((M_PI + 2 * sense * std::atan((u - u0) * scale)) / step);
  }
  std::vector<double> sums(static_cast<std::size_t>(s.views), 0.0);
  std::vector<std::int64_t> counts(static_cast<std::size_t>(s.views), 0);
#pragma omp parallel for schedule(static)
  for (int k = 0; k < s.views; k += stride) {
    double acc = 0;
    std::int64_t n = 0;
    const float* row = s.values.data() + static_cast<std::size_t>(k) * static_cast<std::size_t>(s.cols);
    for (std::size_t j = 0; j < columns.size(); ++j) {
      const int u = columns[j];
      const double mirrored = 2 * u0 - u;
      // The conjugate view, as a fractional index within one turn.
      double f = k + views_on[j];  // views_on lies in (0, period)
      while (f >= period) f -= period;
      const int i0 = static_cast<int>(std::floor(f));
      int i1 = i0 + 1;
      if (i1 >= s.views) i1 -= period;
      if (i0 >= s.views || i1 < 0 || i1 >= s.views) continue;  // a short scan lacks this view
      const double wv = f - i0;
      const int c0 = std::min(static_cast<int>(std::floor(mirrored)), s.cols - 2);
      const double wc = mirrored - c0;
      auto at = [&](int view, int col) {
        return static_cast<double>(
            s.values[static_cast<std::size_t>(view) * static_cast<std::size_t>(s.cols) + static_cast<std::size_t>(col)]);
      };
      const double other =
          (1 - wv) * ((1 - wc) * at(i0, c0) + wc * at(i0, c0 + 1)) + wv * ((1 - wc) * at(i1, c0) + wc * at(i1, c0 + 1));
      const double d = row[u] - other;
      acc += d * d;
      ++n;
    }
    sums[static_cast<std::size_t>(k)] = acc;
    counts[static_cast<std::size_t>(k)] = n;
  }
  for (int k = 0; k < s.views; ++k) {
    const auto b = static_cast<std::size_t>(static_cast<std::int64_t>(k) * kBlocks / s.views);
    m.sum[b] += sums[static_cast<std::size_t>(k)];
    m.count[b] += counts[static_cast<std::size_t>(k)];
  }
  return m;
}

}  // namespace

FanSinogram row_sinogram(const ProjectionStack& b, const CircularTrajectory& orbit, const Detector& detector, double v0_px,
                         double source_to_detector_mm) {
  const int n = b.views;
  if (n < 2 || static_cast<int>(orbit.angles_rad.size()) != n)
    throw std::invalid_argument("row_sinogram: one orbit angle per view expected");
  // Angles are measured from the first view, in [0, 2 pi), turning the way the second one lies:
  // the second angle is the step, which must divide a turn.
  const double step = orbit.angles_rad[1];
  if (!(step > 0)) throw std::invalid_argument("row_sinogram: the first two views are at the same angle");
  const double period = std::round(2 * M_PI / step), exact = 2 * M_PI / period;
  for (int k = 0; k < n; ++k) {
    const double expected = std::fmod(k * exact, 2 * M_PI);
    double d = std::abs(orbit.angles_rad[static_cast<std::size_t>(k)] - expected);
    d = std::min(d, 2 * M_PI - d);
    if (d > 0.05 * exact)
      throw std::invalid_argument("row_sinogram: view " + std::to_string(k) + " is not at an equal step from the first (" +
                                  std::to_string(orbit.angles_rad[static_cast<std::size_t>(k)] * 180 / M_PI) + " deg, expected " +
                                  std::to_string(expected * 180 / M_PI) + ")");
  }
  FanSinogram s;
  s.views = n;
  s.cols = b.cols;
  s.step_rad = exact;
  s.pitch_mm = detector.pitch_u_mm;
  s.source_to_detector_mm = source_to_detector_mm;
  const int row = std::clamp(static_cast<int>(std::lround(v0_px)), 0, b.rows - 1);
  s.values.reserve(static_cast<std::size_t>(n) * static_cast<std::size_t>(b.cols));
  for (int k = 0; k < n; ++k) {
    const float* r = b.view(k) + static_cast<std::size_t>(row) * static_cast<std::size_t>(b.cols);
    s.values.insert(s.values.end(), r, r + b.cols);
  }
  return s;
}

ConjugateRayEstimate conjugate_ray_u0(const FanSinogram& s, double start_px, double search_px) {
  if (s.views <= 0 || s.cols < 2 || s.values.size() != static_cast<std::size_t>(s.views) * static_cast<std::size_t>(s.cols))
    throw std::invalid_argument("conjugate_ray_u0: the sinogram's size disagrees with its views and columns");
  if (!(s.pitch_mm > 0) || !(s.source_to_detector_mm > 0) || s.step_rad == 0)
    throw std::invalid_argument("conjugate_ray_u0: pitch, SDD and the angular step must be set");
  const int period = static_cast<int>(std::lround(2 * M_PI / std::abs(s.step_rad)));
  if (std::abs(period * std::abs(s.step_rad) - 2 * M_PI) > 1e-3 * std::abs(s.step_rad) * period || s.views < period)
    throw std::invalid_argument("conjugate_ray_u0: the views must cover a full turn in equal steps (" + std::to_string(s.views) +
                                " views of " + std::to_string(std::abs(s.step_rad) * 180 / M_PI) + " deg)");
  ConjugateRayEstimate out;
  double best = std::numeric_limits<double>::infinity(), best_other = best;
  for (int sense : {+1, -1}) {
    double lowest = std::numeric_limits<double>::infinity(), at = start_px;  // on every 8th view
    for (double u0 = start_px - search_px; u0 <= start_px + search_px + 1e-9; u0 += 0.5) {
      const double c = mismatch(s, period, u0, sense, 8).total();
      if (c < lowest) {
        lowest = c;
        at = u0;
      }
    }
    if (lowest < best) {
      best_other = best;
      best = lowest;
      out.sense = sense;
      out.u0_px = at;
    } else {
      best_other = std::min(best_other, lowest);
    }
  }
  // Tenth-pixel steps over +-0.6 px about the coarse best; the parabola's vertex, then a jackknife.
  std::vector<double> x;
  std::vector<Mismatch> m;
  for (int i = -6; i <= 6; ++i) {
    x.push_back(out.u0_px + 0.1 * i);
    m.push_back(mismatch(s, period, x.back(), out.sense));
  }
  std::vector<double> y;
  y.reserve(m.size());
  for (const Mismatch& mi : m) y.push_back(mi.total());
  const double v = parabola_vertex(x, y);
  if (!std::isnan(v) && std::abs(v - out.u0_px) <= 0.75) out.u0_px = v;
  std::vector<double> leave_one;
  for (int b = 0; b < kBlocks; ++b) {
    std::vector<double> yb;
    yb.reserve(m.size());
    for (const Mismatch& mi : m) yb.push_back(mi.without(b));
    const double vb = parabola_vertex(x, yb);
    if (!std::isnan(vb)) leave_one.push_back(vb);
  }
  double mean = 0, ss = 0;
  for (double w : leave_one) mean += w / static_cast<double>(leave_one.size());
  for (double w : leave_one) ss += (w - mean) * (w - mean);
  const auto n = static_cast<double>(leave_one.size());
  out.standard_error_px = leave_one.size() > 2 ? std::sqrt(ss * (n - 1) / n) : std::numeric_limits<double>::quiet_NaN();
  for (int part = 0; part < 2; ++part) {
    std::vector<double> yp;
    yp.reserve(m.size());
    for (const Mismatch& mi : m) yp.push_back(mi.in_quarters(part));
    out.u0_quarters_px[part] = parabola_vertex(x, yp);
  }
  const Mismatch at_u0 = mismatch(s, period, out.u0_px, out.sense);
  out.rms_mismatch = std::sqrt(at_u0.total());
  out.rms_mismatch_other_sense = std::sqrt(best_other);
  for (std::int64_t c : at_u0.count) out.pairs += c;
  return out;
}

}  // namespace ctk
