#include "ctk/phantoms/detector_response.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace ctk {

void blur_image(Image& image, double sigma_px) {
  cv::Mat mat(image.rows, image.cols, CV_32F, image.pixels.data());
  cv::GaussianBlur(mat, mat, cv::Size(0, 0), sigma_px, sigma_px, cv::BORDER_REPLICATE);
}

void add_blob(Image& image, const Blob& blob) {
  // Each pixel averages the profile over 4 x 4 points so small blobs keep their sub-pixel centre.
  const int sub = 4;
  const int c0 = std::max(0, static_cast<int>(std::floor(blob.u_px - blob.radius_px - 1)));
  const int c1 = std::min(image.cols - 1, static_cast<int>(std::ceil(blob.u_px + blob.radius_px + 1)));
  const int r0 = std::max(0, static_cast<int>(std::floor(blob.v_px - blob.radius_px - 1)));
  const int r1 = std::min(image.rows - 1, static_cast<int>(std::ceil(blob.v_px + blob.radius_px + 1)));
  const double inv_r2 = 1.0 / (blob.radius_px * blob.radius_px);
  for (int r = r0; r <= r1; ++r)
    for (int c = c0; c <= c1; ++c) {
      double sum = 0;
      for (int b = 0; b < sub; ++b)
        for (int a = 0; a < sub; ++a) {
          const double du = c + (a + 0.5) / sub - 0.5 - blob.u_px, dv = r + (b + 0.5) / sub - 0.5 - blob.v_px;
          sum += std::sqrt(std::max(0.0, 1.0 - (du * du + dv * dv) * inv_r2));
        }
      image.pixels[static_cast<std::size_t>(r) * static_cast<std::size_t>(image.cols) + static_cast<std::size_t>(c)] +=
          static_cast<float>(blob.peak * sum / (sub * sub));
    }
}

void apply_detector_response(Image& signal, double blur_sigma_px, double scatter_fraction) {
  Image scatter;
  if (scatter_fraction > 0) {
    scatter = signal;
    blur_image(scatter, std::max(signal.cols, signal.rows) / 8.0);
  }
  if (blur_sigma_px > 0) blur_image(signal, blur_sigma_px);
  if (scatter_fraction > 0)
    for (std::size_t i = 0; i < signal.pixels.size(); ++i)
      signal.pixels[i] += static_cast<float>(scatter_fraction) * scatter.pixels[i];
}

Image expected_counts(const Image& line_integrals, const CountsModel& model) {
  Image counts = line_integrals;
  for (float& p : counts.pixels) p = static_cast<float>(model.dark_counts + model.flat_counts * std::exp(-double(p)));
  return counts;
}

std::size_t draw_counts(Image& image, const CountsModel& model, std::mt19937_64& rng) {
  constexpr double kMax = 65535.0;
  constexpr double kExactBelow = 1000.0;
  std::normal_distribution<double> normal;
  std::size_t saturated = 0;
  for (float& pixel : image.pixels) {
    const double mean = std::max(0.0, double(pixel) - model.dark_counts);
    double photons;
    if (mean < kExactBelow) {
      photons = static_cast<double>(std::poisson_distribution<long>(mean)(rng));
    } else {
      photons = std::max(0.0, std::round(mean + std::sqrt(mean) * normal(rng)));
    }
    double value = std::round(model.dark_counts) + photons;
    if (value > kMax) {
      value = kMax;
      ++saturated;
    }
    pixel = static_cast<float>(value);
  }
  return saturated;
}

}  // namespace ctk
