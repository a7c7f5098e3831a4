// Scans written by other tools' conventions (NeXus NXtomo, Nikon .xtekct) read back: what the
// files say, matrices that put points where each format's own lab frame puts them, frames bit for bit.
#include <gtest/gtest.h>

#include <random>

#include "../support/vendor_scans.hpp"
#include "../test_support.hpp"
#include "ctk/core/error.hpp"
#include "ctk/core/file_names.hpp"
#include "ctk/core/nexus_tomo.hpp"
#include "ctk/geom/nikon_xtekct.hpp"
#include "ctk/geom/nxtomo_import.hpp"

namespace ctk {
namespace {

namespace fs = std::filesystem;
using testing::ConeSetup;

ConeSetup small_setup() {
  ConeSetup s;
  s.cols = 24;
  s.rows = 20;
  s.views = 12;
  return s;
}

std::vector<Eigen::Vector3d> random_points(int n) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coordinate(-15, 15);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < n; ++i) points.emplace_back(coordinate(rng), coordinate(rng), coordinate(rng));
  return points;
}

template <typename F>
std::string error_of(F f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "no InputError";
}

TEST(NxTomo, ReadsKeysAnglesAndLengthsInMillimetres) {
  const fs::path file = testing::scratch_dir() / "scan.nx";
  const testing::NxTomoContent content = testing::nxtomo_scan(small_setup(), testing::two_balls());
  testing::write_nxtomo(file, content);
  const NxTomo scan = read_nxtomo(file);
  EXPECT_EQ(scan.entry, "/entry");
  EXPECT_EQ(scan.frames, 18);
  EXPECT_EQ(scan.cols, 24);
  EXPECT_EQ(scan.rows, 20);
  EXPECT_TRUE(scan.integer_data);
  EXPECT_EQ(scan.frames_of(NxFrameKind::projection).size(), 12u);
  EXPECT_EQ(scan.frames_of(NxFrameKind::flat), (std::vector<int>{2, 3, 17}));
  EXPECT_EQ(scan.frames_of(NxFrameKind::dark), (std::vector<int>{0, 1}));
  EXPECT_EQ(scan.frames_of(NxFrameKind::invalid).size(), 1u);
  const std::vector<int> projections = scan.frames_of(NxFrameKind::projection);
  for (std::size_t k = 0; k < projections.size(); ++k)
    EXPECT_NEAR(scan.rotation_angle_deg[static_cast<std::size_t>(projections[k])], 30.0 * static_cast<double>(k),
                1e-9);                                    // stored in rad
  EXPECT_NEAR(*scan.x_pixel_size_mm, 0.8, 1e-12);         // stored in m
  EXPECT_NEAR(*scan.y_pixel_size_mm, 0.8, 1e-9);          // stored in um
  EXPECT_NEAR(*scan.sample_to_detector_mm, 200.0, 1e-9);  // stored in cm
  EXPECT_NEAR(*scan.source_to_sample_mm, 200.0, 1e-12);   // stored negative (upstream), in mm
  const NxTomoFrames frames(scan);
  for (int f : {0, 5, 17}) EXPECT_EQ(frames.read(f).pixels, content.frames[static_cast<std::size_t>(f)]);
}

TEST(NxTomo, ImportedMatricesProjectWhereNeXusPlacesTheBeam) {
  const fs::path dir = testing::scratch_dir();
  const ConeSetup setup = small_setup();
  const testing::NxTomoContent content = testing::nxtomo_scan(setup, testing::two_balls());
  testing::write_nxtomo(dir / "scan.nx", content);
  const NxTomo scan = read_nxtomo(dir / "scan.nx");
  const NxTomoPlan plan = plan_nxtomo_import(scan, NxTomoSetup{});
  EXPECT_DOUBLE_EQ(plan.orbit.source_to_axis_mm, 200.0);
  EXPECT_DOUBLE_EQ(plan.orbit.source_to_detector_mm, 400.0);
  const ImportedScan imported = import_nxtomo(scan, plan, dir / "imported.json");
  write_imported_scan(imported, dir / "imported.json");
  const ScanDescription read = read_scan(dir / "imported.json");
  ASSERT_EQ(read.projections.count, 12);
  EXPECT_EQ(read.projections.flat.size(), 3u);
  EXPECT_EQ(read.projections.dark.size(), 2u);
  double worst = 0;
  for (int k = 0; k < 12; ++k)
    for (const Eigen::Vector3d& X : random_points(20)) {
      const Eigen::Vector2d expected = testing::mcstas_projection(setup, 30.0 * k * M_PI / 180.0, X);
      worst = std::max(worst, (read.matrices->geometry.views[static_cast<std::size_t>(k)].P->project(X) - expected).norm());
    }
  EXPECT_LT(worst, 1e-9) << "px";
  // Frames copied out bit for bit, in projection order (the invalid frame left out).
  const std::vector<int> projections = scan.frames_of(NxFrameKind::projection);
  for (int k : {0, 6, 11})
    EXPECT_EQ(read_image(read.projection_path(k), 24, 20).pixels,
              content.frames[static_cast<std::size_t>(projections[static_cast<std::size_t>(k)])]);
  EXPECT_EQ(read_image(read.resolve(read.projections.flat[2]), 24, 20).pixels, content.frames[17]);
}

TEST(NxTomo, RefusesWhatItCannotDescribe) {
  const fs::path dir = testing::scratch_dir();
  testing::NxTomoContent content = testing::nxtomo_scan(small_setup(), testing::two_balls());
  content.data_rank = 2;
  testing::write_nxtomo(dir / "flat.nx", content);
  EXPECT_NE(error_of([&] { read_nxtomo(dir / "flat.nx"); }).find("'/entry/instrument/detector/data': expected three dimensions"),
            std::string::npos);
  content.data_rank = 3;
  content.write_angles = false;
  testing::write_nxtomo(dir / "no-angles.nx", content);
  EXPECT_NE(error_of([&] { read_nxtomo(dir / "no-angles.nx"); }).find("/entry/sample/rotation_angle"), std::string::npos);
  content.write_angles = true;
  content.write_distances = false;
  testing::write_nxtomo(dir / "parallel.nx", content);
  const NxTomo parallel = read_nxtomo(dir / "parallel.nx");
  const std::string e = error_of([&] { plan_nxtomo_import(parallel, NxTomoSetup{}); });
  EXPECT_NE(e.find("instrument/source/distance"), std::string::npos) << e;
  EXPECT_NE(e.find("--sod"), std::string::npos) << e;
  NxTomoSetup given;
  given.source_to_axis_mm = 200;
  given.source_to_detector_mm = 400;
  given.pitch_mm = Eigen::Vector2d(0.8, 0.8);
  EXPECT_EQ(plan_nxtomo_import(parallel, given).orbit.angles_rad.size(), 12u);
  testing::write_text(dir / "text.nx", "not HDF5");
  EXPECT_NE(error_of([&] { read_nxtomo(dir / "text.nx"); }).find("not an HDF5 file"), std::string::npos);
}

TEST(Nikon, MatricesProjectWhereTheXtekctPlacesSourceAxisAndDetector) {
  const fs::path dir = testing::scratch_dir();
  testing::NikonContent content;
  content.setup = small_setup();
  content.object_offset_x_mm = 1.5;
  content.object_tilt_deg = 0.7;
  content.object_roll_deg = -0.4;
  const fs::path file = testing::write_nikon(dir, content, testing::two_balls());
  const NikonScan scan = read_xtekct(file);
  EXPECT_EQ(scan.projections, 12);
  EXPECT_DOUBLE_EQ(scan.white_level, 20000);
  const std::vector<ProjectionMatrix> P = nikon_matrices(scan);
  double worst = 0;
  for (int k = 0; k < 12; ++k)
    for (const Eigen::Vector3d& X : random_points(20))
      worst = std::max(worst, (P[static_cast<std::size_t>(k)].project(X) - testing::nikon_projection(content, k, X)).norm());
  EXPECT_LT(worst, 1e-9) << "px";
  // The other sense is another geometry: the same points land elsewhere.
  EXPECT_GT((nikon_matrices(scan, -1)[3].project(Eigen::Vector3d(10, 0, 0)) - P[3].project(Eigen::Vector3d(10, 0, 0))).norm(),
            1.0);
  const std::vector<fs::path> files = nikon_projection_files(scan);
  ASSERT_EQ(files.size(), 12u);
  EXPECT_EQ(files[0].filename(), "ball_0001.tif");
  EXPECT_EQ(files[11].filename(), "ball_0012.tif");
}

TEST(Nikon, CentreOfRotationGivesTheAxisOffsetAndRoll) {
  const fs::path dir = testing::scratch_dir();
  testing::write_text(
      dir / "s.xtekct",
      "[XTekCT]\nProjections=4\nWhiteLevel=60000\nDetectorPixelsX=100\nDetectorPixelsY=50\nDetectorPixelSizeX=0.2\n"
      "DetectorPixelSizeY=0.2\nSrcToObject=100\nSrcToDetector=500\nAngularStep=90\n"
      "CentreOfRotationTop=0.3\nCentreOfRotationBottom=0.1\nDetectorOffsetX=0.5\n");
  const NikonScan s = read_xtekct(dir / "s.xtekct");
  EXPECT_NEAR(s.axis_offset_mm, 0.2 * 100.0 / 500.0, 1e-12);
  EXPECT_NEAR(s.axis_roll_rad, -std::atan2(0.2, 50 * 0.2), 1e-12);
  EXPECT_DOUBLE_EQ(s.initial_angle_deg, 0.0);
  ASSERT_EQ(s.warnings.size(), 1u);  // the detector offset, read and not modelled
  EXPECT_NE(s.warnings[0].find("DetectorOffsetX"), std::string::npos);
}

TEST(Nikon, RefusesMissingAndMalformedKeys) {
  const fs::path dir = testing::scratch_dir();
  const std::string base =
      "Projections=3\nWhiteLevel=100\nDetectorPixelsX=4\nDetectorPixelsY=4\nDetectorPixelSizeX=0.2\nDetectorPixelSizeY=0.2\n";
  testing::write_text(dir / "a.xtekct", base + "SrcToDetector=500\nAngularStep=1\n");
  EXPECT_NE(error_of([&] { read_xtekct(dir / "a.xtekct"); }).find("key 'SrcToObject': missing"), std::string::npos);
  testing::write_text(dir / "b.xtekct", base + "SrcToObject=100\nSrcToDetector=500\nAngularStep=one\n");
  EXPECT_NE(error_of([&] { read_xtekct(dir / "b.xtekct"); }).find("key 'AngularStep' (line 9): expected a number, got 'one'"),
            std::string::npos);
  testing::write_text(dir / "c.xtekct", base + "SrcToObject=600\nSrcToDetector=500\nAngularStep=1\n");
  EXPECT_NE(error_of([&] { read_xtekct(dir / "c.xtekct"); }).find("not less than SrcToDetector"), std::string::npos);
  testing::write_text(dir / "d.xtekct", base + "Name=x\nSrcToObject=100\nSrcToDetector=500\nAngularStep=1\n");
  testing::write_text(dir / "x_0001.tif", "");
  const std::string e = error_of([&] { nikon_projection_files(read_xtekct(dir / "d.xtekct")); });
  EXPECT_NE(e.find("key 'Projections': 3 projections, but"), std::string::npos) << e;
  EXPECT_NE(e.find("holds 1 files named x_*.tif"), std::string::npos) << e;
  // A distance no scanner has (1e-300 mm made no projection matrix, and the refusal named nothing).
  testing::write_text(dir / "e.xtekct", base + "SrcToObject=1e-300\nSrcToDetector=500\nAngularStep=1\n");
  EXPECT_NE(
      error_of([&] { read_xtekct(dir / "e.xtekct"); }).find("key 'SrcToObject': expected a length between 0.001 and 100000 mm"),
      std::string::npos);
  // InputFolderName may name a folder beside the file, never one elsewhere on the machine.
  fs::create_directories(dir / "inside");
  fs::create_directories(dir.parent_path() / "elsewhere");
  for (const char* folder : {"../elsewhere", "/tmp", "inside/../../elsewhere"}) {
    testing::write_text(dir / "f.xtekct",
                        base + "SrcToObject=100\nSrcToDetector=500\nAngularStep=1\nInputFolderName=" + folder + "\n");
    const NikonScan scan = read_xtekct(dir / "f.xtekct");
    EXPECT_EQ(scan.input_folder, dir) << folder;
    ASSERT_FALSE(scan.warnings.empty()) << folder;
    EXPECT_NE(scan.warnings.back().find("is not a folder beside f.xtekct"), std::string::npos) << scan.warnings.back();
  }
  testing::write_text(dir / "g.xtekct", base + "SrcToObject=100\nSrcToDetector=500\nAngularStep=1\nInputFolderName=inside\n");
  EXPECT_EQ(read_xtekct(dir / "g.xtekct").input_folder, dir / "inside");
}

TEST(FileNames, NaturalOrderComparesDigitRunsByValue) {
  EXPECT_TRUE(natural_less("p_2.tif", "p_10.tif"));
  EXPECT_FALSE(natural_less("p_10.tif", "p_2.tif"));
  EXPECT_TRUE(natural_less("p_0009.tif", "p_0010.tif"));
  EXPECT_TRUE(natural_less("p_7.tif", "p_07.tif"));  // equal value: the shorter run first
  EXPECT_FALSE(natural_less("p_07.tif", "p_7.tif"));
  EXPECT_TRUE(natural_less("a", "a1"));
  EXPECT_TRUE(natural_less("a99999999999999999999999", "a100000000000000000000000"));  // beyond 64 bits
  const fs::path dir = testing::scratch_dir();
  for (const char* n : {"s_10.tif", "s_9.tif", "s_1.tif", "s_100.tif", "t_1.tif", "s_2.exr"}) testing::write_text(dir / n, "");
  std::vector<std::string> names;
  for (const fs::path& f : matching_files(dir, "s_*.tif")) names.push_back(f.filename().string());
  EXPECT_EQ(names, (std::vector<std::string>{"s_1.tif", "s_9.tif", "s_10.tif", "s_100.tif"}));
  EXPECT_TRUE(is_glob("dir/s_*.tif"));
  EXPECT_FALSE(is_glob("dir*/s_%04d.tif"));
}

}  // namespace
}  // namespace ctk
