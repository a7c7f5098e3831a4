// Sphere detection on measured images: five C-arm views of a bead phantom
// (../shared/data/real/surgivisio-carm-fiducials: 16 small metal beads and 2 large ones, an image
// intensifier, edge-enhanced display frames, no ground truth). The beads are dark there, so the
// tests turn each image into bumps (4095 - value) before detecting.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "../test_support.hpp"
#include "ctk/calib/sphere_detection.hpp"

namespace ctk {
namespace {

// The small beads' dark core reaches about 7 px from the centre and fades out by 10 px.
constexpr double kSmallBeadRadiusPx = 8.0;

Image bumps(const std::string& view) {
  Image image = read_image(testing::shared_data_dir() / "surgivisio-carm-fiducials" / ("view_" + view + ".tif"));
  for (float& p : image.pixels) p = (4095.0f - p) / 4095.0f;
  return image;
}

std::vector<SphereDetection> detect(const Image& image) {
  DetectionOptions o;
  o.radius_px = kSmallBeadRadiusPx;
  return detect_spheres(image, o);
}

double pixel(const Image& image, int u, int v) {
  return image.pixels[static_cast<std::size_t>(v) * static_cast<std::size_t>(image.cols) + static_cast<std::size_t>(u)];
}

const char* const kViews[] = {"centered_0", "orbit_30", "orbit_60", "tilt_30", "tilt_60"};

// The 18 beads are the 18 strongest responses in every view, well clear of the rest (the
// frame's corners and edges answer at 0.045 or less, the beads at 0.09 or more).
TEST(SphereDetectionMeasured, FindsTheEighteenBeadsInEveryView) {
  for (const char* view : kViews) {
    const std::vector<SphereDetection> d = detect(bumps(view));
    ASSERT_GE(d.size(), 18u) << view;
    if (d.size() > 18) {
      EXPECT_GT(d[17].response, 2 * d[18].response) << view;
    }
    // Eighteen distinct beads: no two of them within a bead diameter.
    for (int i = 0; i < 18; ++i)
      for (int j = 0; j < i; ++j)
        EXPECT_GT((d[static_cast<std::size_t>(i)].uv - d[static_cast<std::size_t>(j)].uv).norm(), 2 * kSmallBeadRadiusPx)
            << view << ": beads " << j << " and " << i;
  }
}

// Searching a region finds there exactly what the whole image finds there (the filters read the
// pixels around the region, the threshold comes from the region's own noise), and nothing outside.
TEST(SphereDetectionMeasured, ARegionFindsWhatTheWholeImageFindsThere) {
  for (const char* view : {"centered_0", "tilt_60"}) {
    const Image image = bumps(view);
    const std::vector<SphereDetection> whole = detect(image);
    ASSERT_GE(whole.size(), 18u);
    // The box around the six strongest beads, a bead's diameter to spare.
    Eigen::AlignedBox2d box;
    for (int i = 0; i < 6; ++i) box.extend(whole[static_cast<std::size_t>(i)].uv);
    box.min().array() -= 2 * kSmallBeadRadiusPx;
    box.max().array() += 2 * kSmallBeadRadiusPx;
    DetectionOptions o;
    o.radius_px = kSmallBeadRadiusPx;
    o.region = box;
    const std::vector<SphereDetection> inside = detect_spheres(image, o);
    int beads_inside = 0;
    for (int i = 0; i < 18; ++i) {
      const SphereDetection& bead = whole[static_cast<std::size_t>(i)];
      if (!box.contains(bead.uv)) continue;
      ++beads_inside;
      double nearest = 1e9;
      for (const auto& d : inside) nearest = std::min(nearest, (d.uv - bead.uv).norm());
      EXPECT_LT(nearest, 1e-9) << view << ": bead at " << bead.uv.transpose();
    }
    EXPECT_GE(beads_inside, 6) << view;
    Eigen::AlignedBox2d reach = box;
    reach.min().array() -= 1;
    reach.max().array() += 1;
    for (const auto& d : inside) EXPECT_TRUE(reach.contains(d.uv)) << view << ": found outside at " << d.uv.transpose();
  }
}

// Pixel centres sit at integers (scan-format.md): turning the image by 180 degrees maps pixel
// (u, v) to (cols - 1 - u, rows - 1 - v), and every sub-pixel centre must follow exactly. A
// half-pixel slip in the convention would show as a whole pixel here.
TEST(SphereDetectionMeasured, CentresFollowTheImageTurnedHalfAround) {
  const Image image = bumps("orbit_30");
  Image turned = image;
  std::reverse(turned.pixels.begin(), turned.pixels.end());
  const std::vector<SphereDetection> d = detect(image), t = detect(turned);
  ASSERT_GE(t.size(), 18u);
  for (int i = 0; i < 18; ++i) {
    const Eigen::Vector2d expected(image.cols - 1 - d[static_cast<std::size_t>(i)].uv.x(),
                                   image.rows - 1 - d[static_cast<std::size_t>(i)].uv.y());
    double nearest = 1e9;
    for (int j = 0; j < 18; ++j) nearest = std::min(nearest, (t[static_cast<std::size_t>(j)].uv - expected).norm());
    EXPECT_LT(nearest, 1e-3) << "bead " << i << " at " << d[static_cast<std::size_t>(i)].uv.transpose();
  }
}

// Each small bead's sub-pixel centre against one computed here another way: the brightness above
// the median of a ring (radius 12 to 14) summed over radius 10 about the detection, its first
// moments. The two background models differ (the detector fits a plane to the ring from 10 to
// 12 px), and here the plastic frame's edges cross many rings: over the 80 small beads the two
// centres are 0.11 px apart at the median, 0.34 px at the 90th percentile and 0.94 px at worst.
// No ground truth says which is nearer; the median bound fails a refinement that is lost (whole
// pixels give a median near 0.4 px) or shifted. (The large beads, about 15 px across the core, do
// not fit the small beads' windows: their strength is a tenth.)
TEST(SphereDetectionMeasured, CentresAgreeWithAPlainMomentCentroid) {
  std::vector<double> apart;
  for (const char* view : kViews) {
    const Image image = bumps(view);
    const std::vector<SphereDetection> d = detect(image);
    ASSERT_GE(d.size(), 18u) << view;
    int small = 0;
    for (int i = 0; i < 18; ++i) {
      if (d[static_cast<std::size_t>(i)].strength < 0.5 * d.front().strength) continue;
      ++small;
      const Eigen::Vector2d c = d[static_cast<std::size_t>(i)].uv;
      const int u0 = static_cast<int>(std::lround(c.x())), v0 = static_cast<int>(std::lround(c.y()));
      std::vector<float> ring;
      for (int dv = -14; dv <= 14; ++dv)
        for (int du = -14; du <= 14; ++du) {
          const double r = std::hypot(du, dv);
          if (r >= 12 && r <= 14) ring.push_back(static_cast<float>(pixel(image, u0 + du, v0 + dv)));
        }
      std::nth_element(ring.begin(), ring.begin() + static_cast<std::ptrdiff_t>(ring.size() / 2), ring.end());
      const double background = ring[ring.size() / 2];
      double sum = 0;
      Eigen::Vector2d moment = Eigen::Vector2d::Zero();
      for (int dv = -10; dv <= 10; ++dv)
        for (int du = -10; du <= 10; ++du) {
          if (std::hypot(du, dv) > 10) continue;
          const double w = std::max(0.0, pixel(image, u0 + du, v0 + dv) - background);
          sum += w;
          moment += w * Eigen::Vector2d(u0 + du, v0 + dv);
        }
      ASSERT_GT(sum, 0.0) << view << " bead " << i;
      apart.push_back((moment / sum - c).norm());
    }
    EXPECT_EQ(small, 16) << view;
  }
  std::nth_element(apart.begin(), apart.begin() + static_cast<std::ptrdiff_t>(apart.size() / 2), apart.end());
  EXPECT_LT(apart[apart.size() / 2], 0.2);
}

}  // namespace
}  // namespace ctk
