// Binning: a binned pixel is the mean of the pixels it merges, and the binned matrix puts a point
// at the centre of those pixels.
#include <gtest/gtest.h>

#include "ctk/core/image_io.hpp"
#include "ctk/geom/detector_binning.hpp"

namespace ctk {
namespace {

TEST(DetectorBinning, ImageMeansAndMatrixAgree) {
  Image image{7, 5, {}};
  for (int i = 0; i < 35; ++i) image.pixels.push_back(static_cast<float>(i));
  const Image b = binned_image(image, 2);
  ASSERT_EQ(b.cols, 3);
  ASSERT_EQ(b.rows, 2);
  EXPECT_FLOAT_EQ(b.pixels[0], (0 + 1 + 7 + 8) / 4.0f);
  EXPECT_FLOAT_EQ(b.pixels[5], (18 + 19 + 25 + 26) / 4.0f);

  const Detector d{720, 600, 0.6, 0.6};
  const Detector c = binned_detector(d, 3);
  EXPECT_EQ(c.cols, 240);
  EXPECT_DOUBLE_EQ(c.pitch_v_mm, 1.8);
  const ProjectionMatrix P =
      ProjectionMatrix::compose(Intrinsics::from_setup(1500, d, Eigen::Vector2d(351.3, 302.8)),
                                make_rigid(rotation_from_vector(Eigen::Vector3d(0.2, -0.4, 0.1)), Eigen::Vector3d(3, -2, 1000)));
  for (const Eigen::Vector3d& X : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(30, -20, 15)}) {
    const Eigen::Vector2d uv = P.project(X), coarse = binned_matrix(P, 3).project(X);
    // Coarse pixel 0 covers fine pixels 0, 1, 2 and is centred on fine pixel 1.
    EXPECT_NEAR(coarse.x(), (uv.x() - 1) / 3, 1e-9);
    EXPECT_NEAR(coarse.y(), (uv.y() - 1) / 3, 1e-9);
  }
  EXPECT_THROW(binned_detector(d, 0), std::invalid_argument);
}

}  // namespace
}  // namespace ctk
