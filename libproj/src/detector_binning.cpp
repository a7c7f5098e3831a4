#include "ctk/proj/detector_binning.hpp"

#include <stdexcept>
#include <string>

namespace ctk {

Detector binned_detector(const Detector& d, int b) {
  if (b < 1 || b > d.cols || b > d.rows)
    throw std::invalid_argument("binning factor " + std::to_string(b) + " does not fit a " + std::to_string(d.cols) + " x " +
                                std::to_string(d.rows) + " detector");
  return {d.cols / b, d.rows / b, d.pitch_u_mm * b, d.pitch_v_mm * b};
}

Image binned_image(const Image& image, int b) {
  const Detector d = binned_detector({image.cols, image.rows, 1, 1}, b);
  Image out{d.cols, d.rows, std::vector<float>(static_cast<std::size_t>(d.cols) * static_cast<std::size_t>(d.rows), 0.0f)};
  const float scale = 1.0f / static_cast<float>(b * b);
  for (int r = 0; r < d.rows * b; ++r)
    for (int c = 0; c < d.cols * b; ++c)
      out.pixels[static_cast<std::size_t>(r / b) * static_cast<std::size_t>(d.cols) + static_cast<std::size_t>(c / b)] +=
          scale * image.pixels[static_cast<std::size_t>(r) * static_cast<std::size_t>(image.cols) + static_cast<std::size_t>(c)];
  return out;
}

ProjectionMatrix binned_matrix(const ProjectionMatrix& P, int b) {
  // u' = (u - (b - 1) / 2) / b, likewise v'.
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  S(0, 0) = S(1, 1) = 1.0 / b;
  S(0, 2) = S(1, 2) = -0.5 * (b - 1) / b;
  return ProjectionMatrix(Matrix34d(S * P.matrix()));
}

}  // namespace ctk
