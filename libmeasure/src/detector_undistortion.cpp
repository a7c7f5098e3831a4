#include "ctk/measure/detector_undistortion.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <stdexcept>

namespace ctk {

DetectorUndistortion::DetectorUndistortion(int cols, int rows, const RadialDistortion& distortion) : cols_(cols), rows_(rows) {
  if (cols <= 0 || rows <= 0) throw std::invalid_argument("DetectorUndistortion: empty detector");
  const std::size_t n = static_cast<std::size_t>(cols) * static_cast<std::size_t>(rows);
  measured_u_.resize(n);
  measured_v_.resize(n);
  for (int v = 0; v < rows; ++v)
    for (int u = 0; u < cols; ++u) {
      const Eigen::Vector2d ideal(u, v);
      const Eigen::Vector2d m = distortion.measured_from_ideal(ideal);
      const std::size_t i = static_cast<std::size_t>(v) * static_cast<std::size_t>(cols) + static_cast<std::size_t>(u);
      measured_u_[i] = static_cast<float>(m.x());
      measured_v_[i] = static_cast<float>(m.y());
      largest_shift_px_ = std::max(largest_shift_px_, (m - ideal).norm());
      if (m.x() < 0 || m.y() < 0 || m.x() > cols - 1 || m.y() > rows - 1) ++outside_;
    }
}

void DetectorUndistortion::apply(const float* measured, float* ideal, Outside outside) const {
  // OpenCV takes its maps and images as headers over our buffers; nothing is copied.
  const cv::Mat in(rows_, cols_, CV_32FC1, const_cast<float*>(measured));
  cv::Mat out(rows_, cols_, CV_32FC1, ideal);
  const cv::Mat map_u(rows_, cols_, CV_32FC1, const_cast<float*>(measured_u_.data()));
  const cv::Mat map_v(rows_, cols_, CV_32FC1, const_cast<float*>(measured_v_.data()));
  cv::remap(in, out, map_u, map_v, cv::INTER_LINEAR, outside == Outside::zero ? cv::BORDER_CONSTANT : cv::BORDER_REPLICATE,
            cv::Scalar(0));
}

}  // namespace ctk
