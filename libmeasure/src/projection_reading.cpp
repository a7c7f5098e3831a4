#include "ctk/measure/projection_reading.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "ctk/core/error.hpp"

namespace ctk {

namespace {

// A scan written at once with its images (ctk simulate) takes only images of its own run. A binned
// scan's images are read at their stored size and binned (counts, flat and dark alike).
Image read_scan_image(const ScanDescription& scan, const std::filesystem::path& file) {
  std::string written_by;
  const Detector& stored = scan.binning > 1 ? scan.stored_detector : scan.detector;
  Image image = read_image(file, stored.cols, stored.rows, &written_by);
  if (!scan.written_by_run.empty() && !written_by.empty() && written_by != scan.written_by_run)
    throw InputError(file.string(), "",
                     "was written by ctk run " + written_by + ", the scan by run " + scan.written_by_run +
                         ": the folder mixes two runs' files");
  return scan.binning > 1 ? binned_image(image, scan.binning) : image;
}

}  // namespace

std::optional<FlatDark> read_flat_dark(const ScanDescription& scan) {
  if (scan.projections.kind != ProjectionKind::counts) return std::nullopt;
  // Several frames (flats before and after the scan, say) are averaged pixel by pixel.
  auto mean_of = [&](const std::vector<std::string>& names) {
    Image mean = read_scan_image(scan, scan.resolve(names.front()));
    for (std::size_t f = 1; f < names.size(); ++f) {
      const Image next = read_scan_image(scan, scan.resolve(names[f]));
      for (std::size_t i = 0; i < mean.pixels.size(); ++i) mean.pixels[i] += next.pixels[i];
    }
    for (float& x : mean.pixels) x /= static_cast<float>(names.size());
    return mean;
  };
  return FlatDark{mean_of(scan.projections.flat), mean_of(scan.projections.dark)};
}

std::size_t mask_non_finite(Image& image, float* weights) {
  std::vector<std::size_t> bad;
  for (std::size_t i = 0; i < image.pixels.size(); ++i)
    if (!std::isfinite(image.pixels[i])) bad.push_back(i);
  const auto cols = static_cast<std::ptrdiff_t>(image.cols), rows = static_cast<std::ptrdiff_t>(image.rows);
  for (const std::size_t i : bad) {
    const auto r = static_cast<std::ptrdiff_t>(i) / cols, c = static_cast<std::ptrdiff_t>(i) % cols;
    double sum = 0;
    int n = 0;
    for (std::ptrdiff_t dr = -1; dr <= 1; ++dr)
      for (std::ptrdiff_t dc = -1; dc <= 1; ++dc) {
        const std::ptrdiff_t rr = r + dr, cc = c + dc;
        if (rr < 0 || rr >= rows || cc < 0 || cc >= cols) continue;
        const float x = image.pixels[static_cast<std::size_t>(rr * cols + cc)];
        if (std::isfinite(x)) {
          sum += x;
          ++n;
        }
      }
    image.pixels[i] = n > 0 ? static_cast<float>(sum / n) : 0.0f;
    if (weights) weights[i] = 0.0f;
  }
  return bad.size();
}

Image read_line_integrals(const ScanDescription& scan, int view, const std::optional<FlatDark>& flat_dark, float* weights,
                          std::size_t* clamped, std::size_t* non_finite) {
  Image image = read_scan_image(scan, scan.projection_path(view));
  if (scan.projections.kind == ProjectionKind::counts) {
    if (!flat_dark) throw std::invalid_argument("read_line_integrals: a counts scan needs its flat and dark");
    std::size_t count = 0;
    counts_to_line_integrals(image, flat_dark->flat, flat_dark->dark, image.pixels.data(), weights, count);
    if (clamped) *clamped += count;
  }
  const std::size_t masked = mask_non_finite(image, weights);
  if (non_finite) *non_finite += masked;
  return image;
}

}  // namespace ctk
