// Importing scans described elsewhere: a circular orbit by its numbers, and ASTRA cone_vec rows
// (the walnut's own calibrated vectors, read from ../shared/data/real) for files stored in another
// orientation. Points are projected independently, by intersecting the ray with the detector
// plane the vectors describe, and must land where the imported matrices put them.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <fstream>
#include <random>
#include <sstream>

#include "../test_support.hpp"
#include "ctk/geom/geometry_summary.hpp"
#include "ctk/geom/scan_import.hpp"

namespace ctk {
namespace {

// Pixel (column, row) of the image a cone_vec row describes where the ray from the source
// through X meets the detector plane: s + l (X - s) = o + a u + b v, o the centre of pixel (0, 0).
Eigen::Vector2d project_with_vectors(const ConeVec& c, const Detector& described, const Eigen::Vector3d& X) {
  const Eigen::Vector3d s(c[0], c[1], c[2]), d(c[3], c[4], c[5]), u(c[6], c[7], c[8]), v(c[9], c[10], c[11]);
  const Eigen::Vector3d o = d - 0.5 * (described.cols - 1) * u - 0.5 * (described.rows - 1) * v;
  Eigen::Matrix3d A;
  A << u, v, -(X - s);
  const Eigen::Vector3d abl = A.colPivHouseholderQr().solve(s - o);
  return abl.head<2>();
}

TEST(CircularImport, AxisProjectsOntoU0AndSourceCirclesAtSod) {
  CircularOrbit orbit;
  orbit.detector = {239, 190, 0.5984, 0.5984};
  orbit.principal_point_px = {119.2, 95.3};
  orbit.source_to_axis_mm = 1001.3;
  orbit.source_to_detector_mm = 1098.0;
  for (int k = 0; k < 8; ++k) orbit.angles_rad.push_back((0.7 + 45.0 * k) * M_PI / 180);
  const auto vecs = circular_cone_vecs(orbit);
  ASSERT_EQ(vecs.size(), 8u);
  for (std::size_t k = 0; k < vecs.size(); ++k) {
    const ProjectionMatrix P = from_cone_vec(vecs[k], orbit.detector);
    const double t = orbit.angles_rad[k];
    EXPECT_LT((P.source_position() - 1001.3 * Eigen::Vector3d(std::sin(t), std::cos(t), 0)).norm(), 1e-9);
    // Any point of the axis projects onto column u0; the origin onto the principal point.
    EXPECT_NEAR(P.project(Eigen::Vector3d(0, 0, 17)).x(), 119.2, 1e-9);
    EXPECT_LT((P.project(Eigen::Vector3d::Zero()) - orbit.principal_point_px).norm(), 1e-9);
    // Columns run along (cos t, -sin t, 0) and rows downwards (-z), at the magnified pitch.
    const double m = 1098.0 / 1001.3;
    const Eigen::Vector2d du = P.project(Eigen::Vector3d(std::cos(t), -std::sin(t), 0)) - P.project(Eigen::Vector3d::Zero());
    const Eigen::Vector2d dv = P.project(Eigen::Vector3d(0, 0, -1)) - P.project(Eigen::Vector3d::Zero());
    EXPECT_NEAR(du.x(), m / 0.5984, 1e-9);
    EXPECT_NEAR(du.y(), 0, 1e-9);
    EXPECT_NEAR(dv.y(), m / 0.5984, 1e-9);
    // Against the independent ray-plane intersection.
    const Eigen::Vector3d X(12.5, -30.0, 21.0);
    EXPECT_LT((P.project(X) - project_with_vectors(vecs[k], orbit.detector, X)).norm(), 1e-9);
  }
  // The opposite sense mirrors the orbit.
  orbit.sense = -1;
  const ProjectionMatrix Q = from_cone_vec(circular_cone_vecs(orbit)[1], orbit.detector);
  EXPECT_LT(
      (Q.source_position() - 1001.3 * Eigen::Vector3d(-std::sin(orbit.angles_rad[1]), std::cos(orbit.angles_rad[1]), 0)).norm(),
      1e-9);
}

TEST(CircularImport, OneRowDetectorAndBadNumbers) {
  CircularOrbit fan;
  fan.detector = {256, 1, 0.4, 0.4};
  fan.principal_point_px = {127.5, 0};
  fan.source_to_axis_mm = 500;
  fan.source_to_detector_mm = 800;
  fan.angles_rad = {0.0, 1.0};
  const ProjectionMatrix P = from_cone_vec(circular_cone_vecs(fan)[1], fan.detector);
  EXPECT_NEAR(P.project(Eigen::Vector3d(0, 0, 0)).y(), 0.0, 1e-9);  // the mid-plane falls on the one row
  EXPECT_NEAR(P.project(Eigen::Vector3d(0, 0, 0)).x(), 127.5, 1e-9);
  fan.source_to_detector_mm = 400;  // detector between source and axis
  EXPECT_THROW(circular_cone_vecs(fan), std::invalid_argument);
  fan.source_to_detector_mm = 800;
  fan.angles_rad.clear();
  EXPECT_THROW(circular_cone_vecs(fan), std::invalid_argument);
}

// The walnut's vectors describe img = transpose(flipud(stored)): the imported matrices must put a
// point at the stored pixel holding the described one, to 1e-6 px, for every file.
TEST(ConeVecImport, WalnutMatricesAgreeWithTheVectorsOnStoredPixels) {
  const auto dir = testing::shared_data_dir() / "walnut4-tubeV1-10views";
  const std::vector<ConeVec> all = read_cone_vecs(dir / "scan_geom_corrected.geom");
  ASSERT_EQ(all.size(), 1201u);
  const Detector described{768, 972, 0.1496, 0.1496};
  const Detector stored = stored_detector(StoredOrientation::transposed_flipped, described);
  EXPECT_EQ(stored.cols, 972);
  EXPECT_EQ(stored.rows, 768);
  const Eigen::Matrix3d to_stored = described_to_stored(StoredOrientation::transposed_flipped, described);

  // The dataset's derived matrices (projection_matrices_10views.txt) address described pixels.
  std::ifstream derived(dir / "projection_matrices_10views.txt");
  ASSERT_TRUE(derived) << "missing " << (dir / "projection_matrices_10views.txt");
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coord(-25.0, 25.0);
  std::string line;
  int files = 0;
  double worst_vs_vectors = 0, worst_vs_derived = 0;
  while (std::getline(derived, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ss(line);
    int file_index = 0, geom_row = 0;
    Matrix34d D;
    ss >> file_index >> geom_row;
    for (int i = 0; i < 12; ++i) ss >> D(i / 4, i % 4);
    ASSERT_EQ(geom_row, 1200 - file_index);  // the pairing of the official loader
    const ConeVec& c = all[static_cast<std::size_t>(geom_row)];
    const ProjectionMatrix imported(to_stored * from_cone_vec(c, described).matrix());
    for (int n = 0; n < 50; ++n) {
      const Eigen::Vector3d X(coord(rng), coord(rng), coord(rng));
      const Eigen::Vector2d cr = project_with_vectors(c, described, X);            // described (column, row)
      const Eigen::Vector2d expected_stored(cr.y(), described.cols - 1 - cr.x());  // stored[767 - c][r]
      worst_vs_vectors = std::max(worst_vs_vectors, (imported.project(X) - expected_stored).norm());
      const Eigen::Vector3d p = D * X.homogeneous();
      worst_vs_derived = std::max(worst_vs_derived, (p.head<2>() / p.z() - cr).norm());
    }
    ++files;
  }
  EXPECT_EQ(files, 10);
  EXPECT_LT(worst_vs_vectors, 1e-6);
  EXPECT_LT(worst_vs_derived, 1e-6);
}

TEST(ConeVecImport, ScanFileRoundTripsWithAveragedFlats) {
  const auto dir = testing::scratch_dir();
  for (const char* name : {"a.tif", "b.tif", "flat0.tif", "flat1.tif", "dark.tif"}) testing::write_text(dir / name, "x");
  CircularOrbit orbit;
  orbit.detector = {32, 24, 1.0, 1.0};
  orbit.principal_point_px = orbit.detector.centre_px();
  orbit.source_to_axis_mm = 500;
  orbit.source_to_detector_mm = 900;
  orbit.angles_rad = {0.0, 0.5};
  const std::vector<ProjectionMatrix> matrices = circular_matrices(orbit);
  ProjectionSet p;
  p.file_names = {(dir / "a.tif").string(), (dir / "b.tif").string()};
  p.count = 2;
  p.kind = ProjectionKind::counts;
  p.flat = {(dir / "flat0.tif").string(), (dir / "flat1.tif").string()};
  p.dark = {(dir / "dark.tif").string()};
  const auto out = dir / "sub" / "scan.json";
  std::filesystem::create_directories(out.parent_path());
  write_imported_scan(import_matrices(orbit.detector, matrices, p, out), out);
  const ScanDescription scan = read_scan(out);
  EXPECT_TRUE(scan.warnings.empty());
  EXPECT_EQ(scan.projections.file_name(1), "../b.tif");  // relative to the scan's folder
  ASSERT_EQ(scan.projections.flat.size(), 2u);
  EXPECT_EQ(scan.resolve(scan.projections.flat[1]).lexically_normal(), (dir / "flat1.tif").lexically_normal());
  ASSERT_TRUE(scan.matrices);
  EXPECT_NEAR(scan.source_to_detector_mm, 900, 1e-9);
  EXPECT_LT(max_abs_difference(*scan.matrices->geometry.views[1].P, matrices[1]), 1e-12);
}

TEST(GeometrySummary, ACircularOrbitByItsNumbers) {
  // The pepper's setup: SOD 1001.3, SDD 1098 mm, 239 x 190 px of 0.5984 mm.
  CircularOrbit orbit;
  orbit.detector = {239, 190, 0.5984, 0.5984};
  orbit.principal_point_px = orbit.detector.centre_px();
  orbit.source_to_axis_mm = 1001.3;
  orbit.source_to_detector_mm = 1098.0;
  for (int k = 0; k < 9; ++k) orbit.angles_rad.push_back(0.7 * k);
  Geometry g;
  g.detector = orbit.detector;
  for (const ProjectionMatrix& P : circular_matrices(orbit))
    g.views.push_back({static_cast<int>(g.views.size()), "", ViewStatus::ok, "", P, {}, {}});
  g.views.push_back({9, "", ViewStatus::skipped, "no pose", std::nullopt, {}, {}});
  const GeometrySummary s = summarize_geometry(g);
  EXPECT_EQ(s.views, 9);
  EXPECT_NEAR(s.source_to_origin_mm, 1001.3, 1e-9);
  EXPECT_NEAR(s.source_to_detector_mm, 1098.0, 1e-9);
  EXPECT_NEAR(s.magnification, 1098.0 / 1001.3, 1e-12);
  EXPECT_NEAR(s.cone_angle_u_deg, 2 * std::atan(0.5 * 239 * 0.5984 / 1098.0) * 180 / M_PI, 1e-9);
  EXPECT_NEAR(s.cone_angle_v_deg, 2 * std::atan(0.5 * 190 * 0.5984 / 1098.0) * 180 / M_PI, 1e-9);
  EXPECT_NEAR(s.field_of_view_u_mm, 239 * 0.5984 * 1001.3 / 1098.0, 1e-9);
  EXPECT_NEAR(s.voxel_mm, 0.5984 * 1001.3 / 1098.0, 1e-12);
  EXPECT_NE(to_text(s).find("--voxel 0.5457"), std::string::npos) << to_text(s);
  EXPECT_EQ(summarize_geometry(Geometry{}).views, 0);
}

}  // namespace
}  // namespace ctk
