#include "ctk/calib/sphere_detection.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "ctk/core/error.hpp"
#include "ctk/core/statistics.hpp"

namespace ctk {

bool refine_centroid(const Image& im, const Eigen::Vector2d& guess, double radius, SphereDetection& out) {
  Eigen::Vector2d centre = guess;
  // Two passes: the second is centred on the first estimate.
  for (int pass = 0; pass < 2; ++pass) {
    const double inner = radius + 1.5, ring0 = radius + 2.0, ring1 = radius + 4.0;
    const int c0 = static_cast<int>(std::floor(centre.x() - ring1)), c1 = static_cast<int>(std::ceil(centre.x() + ring1));
    const int r0 = static_cast<int>(std::floor(centre.y() - ring1)), r1 = static_cast<int>(std::ceil(centre.y() + ring1));
    if (c0 < 0 || r0 < 0 || c1 >= im.cols || r1 >= im.rows) return false;
    // Background plane a + b du + c dv by least squares over the ring.
    Eigen::Matrix3d AtA = Eigen::Matrix3d::Zero();
    Eigen::Vector3d Atb = Eigen::Vector3d::Zero();
    for (int r = r0; r <= r1; ++r)
      for (int c = c0; c <= c1; ++c) {
        const double du = c - centre.x(), dv = r - centre.y(), d = std::hypot(du, dv);
        if (d < ring0 || d > ring1) continue;
        const Eigen::Vector3d a(1, du, dv);
        AtA += a * a.transpose();
        Atb += a * im.pixels[static_cast<std::size_t>(r) * static_cast<std::size_t>(im.cols) + static_cast<std::size_t>(c)];
      }
    const Eigen::Vector3d plane = AtA.ldlt().solve(Atb);
    Eigen::Vector2d sum(0, 0);
    double weight = 0;
    for (int r = r0; r <= r1; ++r)
      for (int c = c0; c <= c1; ++c) {
        const double du = c - centre.x(), dv = r - centre.y();
        if (std::hypot(du, dv) > inner) continue;
        const double w =
            im.pixels[static_cast<std::size_t>(r) * static_cast<std::size_t>(im.cols) + static_cast<std::size_t>(c)] -
            (plane(0) + plane(1) * du + plane(2) * dv);
        if (w <= 0) continue;
        sum += w * Eigen::Vector2d(c, r);
        weight += w;
      }
    if (!(weight > 0)) return false;
    centre = sum / weight;
    out.strength = weight;
  }
  out.uv = centre;
  return true;
}

void DetectionOptions::validate() const {
  require_option(radius_px > 0, "DetectionOptions.radius_px", "a number above 0", radius_px);
  require_option(noise_sigmas > 0, "DetectionOptions.noise_sigmas", "a number above 0", noise_sigmas);
  require_option(min_roundness >= 0 && min_roundness <= 1, "DetectionOptions.min_roundness", "a number in [0, 1]", min_roundness);
  require_option(max_candidates >= 1, "DetectionOptions.max_candidates", "at least 1", max_candidates);
}

namespace {

// The image less its running median over `window` pixels (odd), float. OpenCV's median takes
// windows wider than 5 only on 8 bits, so the median is taken of the image quantised to 256 levels
// over its range: the step (a 256th of the range) is below the noise of a line-integral image
// whose range is a few units, and only the detection sees it.
cv::Mat without_running_median(const cv::Mat& image, int window) {
  double lo = 0, hi = 0;
  cv::minMaxLoc(image, &lo, &hi);
  cv::Mat out;
  if (!(hi > lo)) return cv::Mat::zeros(image.size(), CV_32F);
  cv::Mat levels, median;
  image.convertTo(levels, CV_8U, 255.0 / (hi - lo), -lo * 255.0 / (hi - lo));
  cv::medianBlur(levels, median, window);
  median.convertTo(out, CV_32F, (hi - lo) / 255.0, lo);
  cv::subtract(image, out, out);
  return out;
}

}  // namespace

std::vector<SphereDetection> detect_spheres(const Image& im, const DetectionOptions& o) {
  o.validate();
  // The searched rectangle; the filters read the image around it (OpenCV filters a submatrix with
  // its parent's pixels beyond the edge), so its responses equal those of the whole image.
  cv::Rect roi(0, 0, im.cols, im.rows);
  if (!o.region.isEmpty()) {
    const int c0 = std::max(0, static_cast<int>(std::floor(o.region.min().x())));
    const int r0 = std::max(0, static_cast<int>(std::floor(o.region.min().y())));
    const int c1 = std::min(im.cols - 1, static_cast<int>(std::ceil(o.region.max().x())));
    const int r1 = std::min(im.rows - 1, static_cast<int>(std::ceil(o.region.max().y())));
    if (c1 - c0 < 2 || r1 - r0 < 2) return {};
    roi = cv::Rect(c0, r0, c1 - c0 + 1, r1 - r0 + 1);
  }
  const double s = std::max(0.7, o.radius_px / std::sqrt(2.0));
  const cv::Mat whole(im.rows, im.cols, CV_32F, const_cast<float*>(im.pixels.data()));
  // What the filters and centroids work on: the image, or the remainder after its running median
  // over a window two sphere diameters across (a disc covers a sixth of it, two touching discs a
  // third, so the median stays the background), taken over the region and the filters' reach.
  cv::Rect frame(0, 0, im.cols, im.rows);
  cv::Mat source = whole;
  Image remainder;
  if (o.edge_preserving_background) {
    const int half = std::max(2, static_cast<int>(std::lround(2 * o.radius_px)));
    const int reach = half + static_cast<int>(std::ceil(8 * s + o.radius_px)) + 8;
    frame = cv::Rect(roi.x - reach, roi.y - reach, roi.width + 2 * reach, roi.height + 2 * reach) & frame;
    const cv::Mat remainder_mat = without_running_median(whole(frame), 2 * half + 1);
    remainder.cols = frame.width;
    remainder.rows = frame.height;
    remainder.pixels.assign(remainder_mat.begin<float>(), remainder_mat.end<float>());
    source = cv::Mat(remainder.rows, remainder.cols, CV_32F, remainder.pixels.data());
    roi -= frame.tl();
  }
  const Image& centroid_image = o.edge_preserving_background ? remainder : im;
  // Difference of Gaussians matched to a disc of radius R: sigma R / sqrt(2) against 2x that.
  const cv::Mat image = source(roi);
  cv::Mat narrow, wide, dog;
  cv::GaussianBlur(image, narrow, cv::Size(0, 0), s, s, cv::BORDER_REPLICATE);
  cv::GaussianBlur(image, wide, cv::Size(0, 0), 2 * s, 2 * s, cv::BORDER_REPLICATE);
  cv::subtract(narrow, wide, dog);
  // Local maxima over a window the size of a sphere, above a noise-scaled threshold.
  cv::Mat dilated;
  const int k = 2 * static_cast<int>(std::ceil(o.radius_px)) + 1;
  cv::dilate(dog, dilated, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(k, k)));
  // Threshold from the noise: a robust spread (median absolute deviation) of the response, so
  // the strong walls do not raise it.
  std::vector<float> sample;
  sample.reserve(static_cast<std::size_t>(roi.area() / 16 + 1));
  for (int r = 0; r < roi.height; r += 4)
    for (int c = 0; c < roi.width; c += 4) sample.push_back(dog.at<float>(r, c));
  const float centre = median_in_place(sample);
  for (float& x : sample) x = std::abs(x - centre);
  const float threshold = centre + o.noise_sigmas * 1.4826f * std::max(median_in_place(sample), 1e-12f);
  std::vector<SphereDetection> candidates;
  for (int r = 1; r + 1 < roi.height; ++r) {
    const float* d = dog.ptr<float>(r);
    const float* m = dilated.ptr<float>(r);
    for (int c = 1; c + 1 < roi.width; ++c) {
      if (d[c] <= threshold || d[c] < m[c]) continue;
      // A sphere is a bump (both curvatures strongly negative); a wall's edge is a ridge.
      const double dxx = narrow.at<float>(r, c + 1) - 2.0 * narrow.at<float>(r, c) + narrow.at<float>(r, c - 1);
      const double dyy = narrow.at<float>(r + 1, c) - 2.0 * narrow.at<float>(r, c) + narrow.at<float>(r - 1, c);
      const double dxy = 0.25 * (narrow.at<float>(r + 1, c + 1) - narrow.at<float>(r + 1, c - 1) -
                                 narrow.at<float>(r - 1, c + 1) + narrow.at<float>(r - 1, c - 1));
      const double mean_curvature = 0.5 * (dxx + dyy), spread = std::sqrt(0.25 * (dxx - dyy) * (dxx - dyy) + dxy * dxy);
      const double l_large = mean_curvature - spread, l_small = mean_curvature + spread;  // both < 0 for a bump
      if (!(l_small < 0) || l_small > o.min_roundness * l_large) continue;
      candidates.push_back({Eigen::Vector2d(c + roi.x, r + roi.y), 0.0, d[c]});  // in the frame
    }
  }
  std::sort(candidates.begin(), candidates.end(), [](const auto& a, const auto& b) { return a.response > b.response; });
  if (static_cast<int>(candidates.size()) > o.max_candidates) candidates.resize(static_cast<std::size_t>(o.max_candidates));
  std::vector<SphereDetection> detections;
  const Eigen::Vector2d frame_origin(frame.x, frame.y);
  for (const auto& cand : candidates) {
    SphereDetection d = cand;
    if (!refine_centroid(centroid_image, cand.uv, o.radius_px, d)) continue;
    d.uv += frame_origin;
    detections.push_back(d);
  }
  return detections;
}

}  // namespace ctk
