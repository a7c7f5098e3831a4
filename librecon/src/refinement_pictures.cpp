#include "ctk/recon/refinement_pictures.hpp"

#include <algorithm>
#include <cmath>

#include "ctk/core/image_io.hpp"
#include "ctk/core/slice_preview.hpp"

namespace ctk {

namespace {

void write_central_slice(const Volume& x, float high, const std::filesystem::path& file) {
  write_slice_preview(x, 2, x.layout.size[2] / 2, 0.0f, high, "1/mm", file);
}

// After less before on the same central slice, mid-grey 0, black and white at the largest change,
// so that a change too small to see between the two pictures shows.
void write_difference_slice(const Volume& before, const Volume& after, const std::filesystem::path& file) {
  Volume d = after;
  float largest = 1e-12f;
  for (std::size_t i = 0; i < d.data.size(); ++i) {
    d.data[i] -= before.data[i];
    largest = std::max(largest, std::abs(d.data[i]));
  }
  write_slice_preview(d, 2, d.layout.size[2] / 2, -largest, largest, "1/mm", file);
}

// Each pixel's mean held-out residual over its standard error, grey 0 at mid-grey, black at -10
// and white at +10 or beyond (rows left out of the costs at 0). A one-row detector is drawn as a
// band 48 rows high.
void write_pattern_picture(const DetectorPattern& p, const std::filesystem::path& file) {
  const int height = p.rows == 1 ? 48 : p.rows;
  Volume z(VolumeLayout::centred({p.cols, height, 1}, Eigen::Vector3d::Ones()));
  for (int row = 0; row < height; ++row)
    for (int c = 0; c < p.cols; ++c) {
      const std::size_t i =
          static_cast<std::size_t>(p.rows == 1 ? 0 : row) * static_cast<std::size_t>(p.cols) + static_cast<std::size_t>(c);
      const double se = p.standard_error[i];
      z.at(c, row, 0) =
          p.used[i] && se > 0 && std::isfinite(se) ? static_cast<float>(std::clamp(p.mean[i] / se, -10.0, 10.0)) : 0.0f;
    }
  write_slice_png(z, 2, 0, -10.0f, 10.0f, file);
}

}  // namespace

std::vector<std::string> write_refinement_pictures(const RefinementResult& r, const std::filesystem::path& stem) {
  const auto named = [&](const char* what) { return std::filesystem::path(stem.string() + "." + what + ".png"); };
  const float high = preview_ceiling(r.volume_before);  // one grey scale for both slices
  write_central_slice(r.volume_before, high, named("before"));
  write_central_slice(r.volume_after, high, named("after"));
  write_difference_slice(r.volume_before, r.volume_after, named("difference"));
  write_pattern_picture(r.residual_pattern, named("pattern"));
  return {named("before").filename().string(), named("after").filename().string(), named("difference").filename().string(),
          named("pattern").filename().string()};
}

}  // namespace ctk
