// RTK's geometry XML both ways. A view's RTK parameters place the source and the detector in
// space (RTK's rotated frame, turned back into the volume); a point must land on the pixel where
// the ray from that source through it meets that detector, under the documented pixel map, and
// ctk's matrices must survive the trip to RTK's parameters and back to 1e-9 px.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>

#include "../test_support.hpp"
#include "ctk/core/error.hpp"
#include "ctk/geom/rtk_geometry.hpp"

namespace ctk {
namespace {

namespace fs = std::filesystem;

const Detector detector{300, 200, 0.4, 0.4};

// The rotated frame's axes in the volume, from RTK's own description of its angles: the volume
// turns by Ry(-gantry), then Rx(-out of plane), then Rz(-in plane).
Eigen::Matrix3d volume_to_rotated(const RtkProjection& p) {
  auto turn = [](const Eigen::Vector3d& axis, double deg) {
    return Eigen::AngleAxisd(deg * M_PI / 180, axis).toRotationMatrix();
  };
  return turn(Eigen::Vector3d::UnitZ(), -p.in_plane_deg) * turn(Eigen::Vector3d::UnitX(), -p.out_of_plane_deg) *
         turn(Eigen::Vector3d::UnitY(), -p.gantry_deg);
}

// Pixel of X by ray casting: the source at (sx, sy, sid) in the rotated frame, the detector
// plane at z = sid - sdd with its origin at (px, py); detector mm to pixels by the documented map.
Eigen::Vector2d cast(const RtkProjection& p, const Eigen::Vector3d& X) {
  const Eigen::Matrix3d R = volume_to_rotated(p);
  const Eigen::Vector3d x = R * X;
  const Eigen::Vector3d s(p.source_offset_x_mm, p.source_offset_y_mm, p.source_to_isocentre_mm);
  const double plane = p.source_to_isocentre_mm - p.source_to_detector_mm;
  const double l = (plane - s.z()) / (x.z() - s.z());
  const Eigen::Vector3d hit = s + l * (x - s);
  const double dx = hit.x() - p.projection_offset_x_mm, dy = hit.y() - p.projection_offset_y_mm;
  return {0.5 * (detector.cols - 1) + dx / detector.pitch_u_mm, 0.5 * (detector.rows - 1) - dy / detector.pitch_v_mm};
}

RtkProjection random_view(std::mt19937& rng) {
  std::uniform_real_distribution<double> angle(0, 360), small(-15, 15), offset(-20, 20), sid(600, 1200);
  RtkProjection p;
  p.source_to_isocentre_mm = sid(rng);
  p.source_to_detector_mm = p.source_to_isocentre_mm + 400;
  p.gantry_deg = angle(rng);
  p.out_of_plane_deg = small(rng);
  p.in_plane_deg = small(rng);
  p.source_offset_x_mm = offset(rng);
  p.source_offset_y_mm = offset(rng);
  p.projection_offset_x_mm = offset(rng);
  p.projection_offset_y_mm = offset(rng);
  return p;
}

TEST(RtkGeometry, MatricesPutPointsWhereTheRayMeetsTheDetector) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coordinate(-40, 40);
  for (int view = 0; view < 50; ++view) {
    const RtkProjection p = random_view(rng);
    const ProjectionMatrix P = from_rtk(p, detector, RtkRows::flipped);
    for (int i = 0; i < 20; ++i) {
      const Eigen::Vector3d X(coordinate(rng), coordinate(rng), coordinate(rng));
      EXPECT_LT((P.project(X) - cast(p, X)).norm(), 1e-9) << "view " << view;
      EXPECT_GT(P.depth(X), 0) << "in front of the source";
    }
  }
}

TEST(RtkGeometry, TheStandardCircleLooksAlongMinusZAtGantryZero) {
  // Gantry 0, no offsets: the source on +z at sid, the isocentre on the detector's centre, a
  // point on +x to the right (larger column), a point on +y up (smaller row).
  RtkProjection p;
  p.source_to_isocentre_mm = 1000;
  p.source_to_detector_mm = 1500;
  const ProjectionMatrix P = from_rtk(p, detector, RtkRows::flipped);
  EXPECT_LT((P.source_position() - Eigen::Vector3d(0, 0, 1000)).norm(), 1e-9);
  EXPECT_LT((P.project(Eigen::Vector3d::Zero()) - detector.centre_px()).norm(), 1e-9);
  EXPECT_NEAR(P.project(Eigen::Vector3d(10, 0, 0)).x() - detector.centre_px().x(), 10 * 1.5 / 0.4, 1e-9);
  EXPECT_NEAR(P.project(Eigen::Vector3d(0, 10, 0)).y() - detector.centre_px().y(), -10 * 1.5 / 0.4, 1e-9);
  // Gantry 90: the source turns to +x (RTK's Ry(-gantry) of the volume).
  p.gantry_deg = 90;
  EXPECT_LT((from_rtk(p, detector, RtkRows::flipped).source_position() - Eigen::Vector3d(1000, 0, 0)).norm(), 1e-9);
}

TEST(RtkGeometry, CtkMatricesSurviveRtkParametersToANanopixel) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> coordinate(-40, 40);
  std::vector<ProjectionMatrix> originals;
  for (int view = 0; view < 40; ++view) originals.push_back(from_rtk(random_view(rng), detector, RtkRows::flipped));
  // And ctk's own kinds: an out-of-plane angle of exactly 90 deg (the axis of a circular import
  // along RTK's source direction) sits where the Euler angles are degenerate.
  RtkProjection degenerate;
  degenerate.source_to_isocentre_mm = 800;
  degenerate.source_to_detector_mm = 1100;
  degenerate.out_of_plane_deg = 90;
  degenerate.gantry_deg = 30;
  degenerate.in_plane_deg = 10;
  originals.push_back(from_rtk(degenerate, detector, RtkRows::flipped));
  degenerate.out_of_plane_deg = 270;
  originals.push_back(from_rtk(degenerate, detector, RtkRows::flipped));

  std::vector<RtkProjection> views;
  for (const ProjectionMatrix& P : originals) views.push_back(to_rtk(P, detector, RtkRows::flipped));
  const fs::path file = testing::scratch_dir() / "rtk-round-trip.xml";
  write_rtk_geometry(views, RtkRows::flipped, file);
  const RtkGeometry read = read_rtk_geometry(file);
  ASSERT_EQ(read.views.size(), originals.size());
  EXPECT_EQ(read.rows, RtkRows::flipped) << "named in the file's comment";
  for (std::size_t v = 0; v < originals.size(); ++v) {
    const ProjectionMatrix back = from_rtk(read.views[v], detector, *read.rows);
    for (int i = 0; i < 20; ++i) {
      const Eigen::Vector3d X(coordinate(rng), coordinate(rng), coordinate(rng));
      EXPECT_LT((back.project(X) - originals[v].project(X)).norm(), 1e-9) << "view " << v;
    }
  }
}

TEST(RtkGeometry, WritesConstantParametersOnceAsRtkDoes) {
  std::vector<RtkProjection> views(3);
  for (std::size_t v = 0; v < views.size(); ++v) {
    views[v].source_to_isocentre_mm = 1000;
    views[v].source_to_detector_mm = 1536;
    views[v].gantry_deg = 120.0 * static_cast<double>(v);
  }
  const fs::path file = testing::scratch_dir() / "rtk-circle.xml";
  write_rtk_geometry(views, RtkRows::as_stored, file);
  std::ifstream in(file);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto count = [&](const std::string& what) {
    std::size_t n = 0;
    for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
    return n;
  };
  EXPECT_EQ(count("<SourceToDetectorDistance>"), 1u);
  EXPECT_EQ(count("<GantryAngle>"), 3u);
  EXPECT_EQ(count("<ProjectionOffsetX>"), 0u) << "0 is RTK's default";
  EXPECT_EQ(count("<Matrix>"), 3u);
  EXPECT_NE(text.find("<RTKThreeDCircularGeometry version=\"3\">"), std::string::npos);
}

TEST(RtkGeometry, ParametersBeforeTheProjectionsHoldForEach) {
  const fs::path file = testing::scratch_dir() / "rtk-global.xml";
  std::ofstream(file) << "<?xml version=\"1.0\"?>\n<!DOCTYPE RTKGEOMETRY>\n<RTKThreeDCircularGeometry version=\"2\">\n"
                         "<SourceToIsocenterDistance>1000</SourceToIsocenterDistance>\n"
                         "<SourceToDetectorDistance>1536</SourceToDetectorDistance>\n"
                         "<Projection><GantryAngle>0</GantryAngle></Projection>\n"
                         "<Projection><GantryAngle>90</GantryAngle><ProjectionOffsetX>5</ProjectionOffsetX></Projection>\n"
                         "<Projection><GantryAngle>180</GantryAngle></Projection>\n"
                         "</RTKThreeDCircularGeometry>\n";
  const auto [views, rows, holder_z_on_rtk_y] = read_rtk_geometry(file);
  ASSERT_EQ(views.size(), 3u);
  EXPECT_FALSE(rows) << "a file not written by ctk names no pixel map";
  EXPECT_FALSE(holder_z_on_rtk_y) << "nor a volume frame of ctk's: its matrices are read in their own frame";
  EXPECT_EQ(views[2].source_to_detector_mm, 1536);
  EXPECT_EQ(views[1].projection_offset_x_mm, 5);
  EXPECT_EQ(views[2].projection_offset_x_mm, 5) << "a value holds until set anew, as RTK reads it";
  EXPECT_EQ(views[2].gantry_deg, 180);
}

TEST(RtkGeometry, ViewsRtkCannotHoldAreRefusedSayingWhy) {
  std::mt19937 rng(3);
  const ProjectionMatrix P = from_rtk(random_view(rng), detector, RtkRows::flipped);
  Matrix34d skewed = P.matrix();
  skewed.row(0) += 0.01 * skewed.row(1);
  EXPECT_THROW(to_rtk(ProjectionMatrix(skewed), detector, RtkRows::flipped), std::invalid_argument);
  Matrix34d mirrored = P.matrix();
  mirrored.row(0) = 2 * detector.centre_px().x() * mirrored.row(2) - mirrored.row(0);  // u -> cols - 1 - u
  try {
    to_rtk(ProjectionMatrix(mirrored), detector, RtkRows::flipped);
    FAIL() << "a mirrored detector was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("mirrored"), std::string::npos) << e.what();
  }
  EXPECT_EQ(rtk_rows_for(P), RtkRows::flipped);
  EXPECT_EQ(rtk_rows_for(ProjectionMatrix(mirrored)), RtkRows::as_stored);
}

TEST(RtkGeometry, AMirroredDetectorIsHeldWithTheRowsAsStored) {
  // Images stored as a mirror of what the source sees (the CWI walnuts'): RTK reads them as
  // stored, its y along the rows; the same cast with v and y in one sense.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> coordinate(-40, 40);
  for (int view = 0; view < 20; ++view) {
    const RtkProjection p = random_view(rng);
    const ProjectionMatrix P = from_rtk(p, detector, RtkRows::as_stored);
    EXPECT_EQ(rtk_rows_for(P), RtkRows::as_stored);
    const RtkProjection back = to_rtk(P, detector, RtkRows::as_stored);
    for (int i = 0; i < 10; ++i) {
      const Eigen::Vector3d X(coordinate(rng), coordinate(rng), coordinate(rng));
      const Eigen::Vector2d flipped = cast(p, X);
      EXPECT_LT((P.project(X) - Eigen::Vector2d(flipped.x(), detector.rows - 1 - flipped.y())).norm(), 1e-9);
      EXPECT_LT((from_rtk(back, detector, RtkRows::as_stored).project(X) - P.project(X)).norm(), 1e-9);
    }
  }
}

TEST(RtkGeometry, BadFilesNameTheFileAndTheElement) {
  const std::string header = "<?xml version=\"1.0\"?>\n<RTKThreeDCircularGeometry version=\"3\">\n";
  const std::string distances =
      "<SourceToIsocenterDistance>1000</SourceToIsocenterDistance><SourceToDetectorDistance>1536</SourceToDetectorDistance>";
  struct Case {
    std::string body, where;
  };
  const std::vector<Case> cases = {
      {"<Projection><GantryAngle>0</GantryAngle></Projection>", "Projection[0]"},  // no distances
      {distances + "<Projection><GantryAngle>ten</GantryAngle></Projection>", "Projection[0].GantryAngle"},
      {distances + "<Projection><GantryAngle>0</GantryAngle><Matrix>1 2 3</Matrix></Projection>", "Projection[0].Matrix"},
      {distances + "<Projection><GantryAngle>0</GantryAngle><Matrix>-1536 0 0 0 0 -1536 0 0 0 0 1 -999</Matrix></Projection>",
       "Projection[0].Matrix"},  // disagrees with the sid of 1000
      {"<SourceToIsocenterDistance>1000</SourceToIsocenterDistance><SourceToDetectorDistance>0</SourceToDetectorDistance>"
       "<Projection/>",
       "Projection[0].SourceToDetectorDistance"},  // parallel
      {distances + "<RadiusCylindricalDetector>1536</RadiusCylindricalDetector><Projection/>", "RadiusCylindricalDetector"},
      {distances, ""},  // no projection
  };
  const fs::path dir = testing::scratch_dir();
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const fs::path file = dir / ("rtk-bad-" + std::to_string(i) + ".xml");
    std::ofstream(file) << header << cases[i].body << "\n</RTKThreeDCircularGeometry>\n";
    try {
      read_rtk_geometry(file);
      ADD_FAILURE() << "case " << i << " was read";
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), file.string());
      EXPECT_EQ(e.where(), cases[i].where) << "case " << i << ": " << e.what();
    }
  }
  const fs::path not_xml = dir / "rtk-not-xml.xml";
  std::ofstream(not_xml) << "<RTKThreeDCircularGeometry><Projection>";
  EXPECT_THROW(read_rtk_geometry(not_xml), InputError);
  const fs::path other = dir / "rtk-other.xml";
  std::ofstream(other) << "<?xml version=\"1.0\"?><Geometry/>";
  EXPECT_THROW(read_rtk_geometry(other), InputError);
}

}  // namespace
}  // namespace ctk
