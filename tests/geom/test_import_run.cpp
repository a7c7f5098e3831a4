// The import workflow (import_run.hpp): requests that name their fields when refused, a circular
// scan imported from images on disk and read back as every command reads it, its images checked
// and its inputs never written over.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iterator>

#include "../test_support.hpp"
#include "ctk/core/error.hpp"
#include "ctk/core/image_io.hpp"
#include "ctk/geom/import_run.hpp"

namespace ctk {
namespace {

namespace fs = std::filesystem;

// Three float TIFFs of 40 x 30 (line integrals), named proj_0.tif .. proj_2.tif.
CircularImportRequest three_views(const fs::path& dir) {
  for (int v = 0; v < 3; ++v)
    write_image_float(Image{40, 30, std::vector<float>(40 * 30, 0.1f * static_cast<float>(v))},
                      dir / ("proj_" + std::to_string(v) + ".tif"));
  CircularImportRequest r;
  r.out = dir / "scan.json";
  r.files = {(dir / "proj_%d.tif").string()};
  r.count = 3;
  r.kind = ProjectionKind::line_integrals;
  r.pitch_mm = {0.5};
  r.sod_mm = 500;
  r.sdd_mm = 800;
  r.step_deg = 120;
  return r;
}

std::string contents(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

TEST(OptionsValidation, ImportRequests) {
  using testing::expect_option_refused;
  CircularImportRequest circular;
  circular.out = "scan.json";
  circular.files = {"p_%04d.tif"};
  circular.pitch_mm = {0.5};
  circular.sod_mm = 500;
  circular.sdd_mm = 800;
  EXPECT_NO_THROW(circular.validate());
  expect_option_refused(
      circular, [](auto& r) { r.out.clear(); }, "ImportRequest.out");
  expect_option_refused(
      circular, [](auto& r) { r.bin = 0; }, "ImportRequest.bin");
  expect_option_refused(
      circular, [](auto& r) { r.files.clear(); }, "ProjectionImportRequest.files");
  expect_option_refused(
      circular, [](auto& r) { r.count = -1; }, "ProjectionImportRequest.count");
  expect_option_refused(
      circular,
      [](auto& r) {
        r.detector = std::array<int, 2>{0, 10};
      },
      "ProjectionImportRequest.detector");
  expect_option_refused(
      circular,
      [](auto& r) {
        r.pitch_mm = {0.5, -1};
      },
      "ProjectionImportRequest.pitch_mm");
  expect_option_refused(
      circular, [](auto& r) { r.pitch_mm.clear(); }, "CircularImportRequest.pitch_mm");
  expect_option_refused(
      circular, [](auto& r) { r.sod_mm = 0; }, "CircularImportRequest.sod_mm");
  expect_option_refused(
      circular, [](auto& r) { r.sdd_mm = 400; }, "CircularImportRequest.sdd_mm");
  expect_option_refused(
      circular, [](auto& r) { r.step_deg = std::nan(""); }, "CircularImportRequest.step_deg");
  expect_option_refused(
      circular, [](auto& r) { r.sense = 0; }, "CircularImportRequest.sense");
  // A caller's names for the fields (the command line's options) are the ones messages use.
  expect_option_refused(
      circular,
      [](auto& r) {
        r.sdd_mm = 400;
        r.field_names = [](const std::string& f) { return "--" + f; };
      },
      "--sdd_mm");

  ConeVecImportRequest cone_vec;
  static_cast<ProjectionImportRequest&>(cone_vec) = circular;
  expect_option_refused(
      cone_vec, [](auto& r) { r.vectors.clear(); }, "ConeVecImportRequest.vectors");
  RtkImportRequest rtk;
  static_cast<ProjectionImportRequest&>(rtk) = circular;
  expect_option_refused(
      rtk, [](auto& r) { r.geometry.clear(); }, "RtkImportRequest.geometry");
  rtk.geometry = "g.xml";
  expect_option_refused(
      rtk, [](auto& r) { r.pitch_mm.clear(); }, "RtkImportRequest.pitch_mm");
  MatricesImportRequest matrices;
  static_cast<ProjectionImportRequest&>(matrices) = circular;
  expect_option_refused(
      matrices, [](auto& r) { r.matrices.clear(); }, "MatricesImportRequest.matrices");

  NxTomoImportRequest nxtomo;
  nxtomo.out = "scan.json";
  nxtomo.nexus = "scan.nx";
  EXPECT_NO_THROW(nxtomo.validate());
  expect_option_refused(
      nxtomo, [](auto& r) { r.nexus.clear(); }, "NxTomoImportRequest.nexus");
  expect_option_refused(
      nxtomo, [](auto& r) { r.setup.source_to_axis_mm = -5; }, "NxTomoImportRequest.setup.source_to_axis_mm");
  expect_option_refused(
      nxtomo, [](auto& r) { r.setup.source_to_detector_mm = 0; }, "NxTomoImportRequest.setup.source_to_detector_mm");
  expect_option_refused(
      nxtomo, [](auto& r) { r.setup.pitch_mm = Eigen::Vector2d(0.1, 0); }, "NxTomoImportRequest.setup.pitch_mm");
  expect_option_refused(
      nxtomo, [](auto& r) { r.setup.sense = 2; }, "NxTomoImportRequest.setup.sense");
  NikonImportRequest nikon;
  nikon.out = "scan.json";
  nikon.xtekct = "scan.xtekct";
  EXPECT_NO_THROW(nikon.validate());
  expect_option_refused(
      nikon, [](auto& r) { r.xtekct.clear(); }, "NikonImportRequest.xtekct");
  expect_option_refused(
      nikon, [](auto& r) { r.sense = -2; }, "NikonImportRequest.sense");
}

TEST(ImportRun, ACircularScanFromItsImagesReadsBackAsTheOrbitItDescribes) {
  const fs::path dir = testing::scratch_dir();
  const CircularImportRequest r = three_views(dir);
  const ImportRun run = run_import(r);
  // The detector's size from the first image, said so; the scan as read back from the file.
  EXPECT_EQ(run.scan.detector.cols, 40);
  EXPECT_EQ(run.scan.detector.rows, 30);
  ASSERT_FALSE(run.notes.empty());
  EXPECT_NE(run.notes.front().find("detector 40 x 30 px"), std::string::npos) << run.notes.front();
  EXPECT_TRUE(run.warnings.empty());
  EXPECT_EQ(run.scan.projections.count, 3);
  ASSERT_TRUE(run.scan.matrices);
  CircularOrbit orbit;
  orbit.detector = {40, 30, 0.5, 0.5};
  orbit.principal_point_px = orbit.detector.centre_px();
  orbit.source_to_axis_mm = 500;
  orbit.source_to_detector_mm = 800;
  orbit.angles_rad = {0, 120 * M_PI / 180, 240 * M_PI / 180};
  const std::vector<ProjectionMatrix> expected = circular_matrices(orbit);
  for (std::size_t v = 0; v < 3; ++v) {
    const auto& P = run.scan.matrices->geometry.views[v].P;
    ASSERT_TRUE(P);
    EXPECT_LT((P->project(Eigen::Vector3d(3, -4, 5)) - expected[v].project(Eigen::Vector3d(3, -4, 5))).norm(), 1e-9);
  }
  EXPECT_NE(run.brief().find("(3 views, detector 40 x 30)"), std::string::npos) << run.brief();
  EXPECT_NE(run.report().find("magnification 1.6"), std::string::npos) << run.report();

  // Binned 2 x 2: recorded, the stored detector kept.
  CircularImportRequest binned = r;
  binned.out = dir / "binned.json";
  binned.bin = 2;
  const ImportRun b = run_import(binned);
  EXPECT_EQ(b.scan.binning, 2);
  EXPECT_EQ(b.scan.detector.cols, 20);
  EXPECT_EQ(b.scan.stored_detector.cols, 40);
  EXPECT_NE(b.brief().find("binned 2 x 2 from 40 x 30"), std::string::npos) << b.brief();
}

TEST(ImportRun, ImagesAreCheckedAndInputsNeverWrittenOver) {
  const fs::path dir = testing::scratch_dir();
  const CircularImportRequest good = three_views(dir);
  // One missing file of four: imported, with a warning naming it.
  CircularImportRequest four = good;
  four.count = 4;
  four.out = dir / "four.json";
  const ImportRun run = run_import(four);
  ASSERT_EQ(run.warnings.size(), 1u);
  EXPECT_NE(run.warnings.front().find("1 of 4 projection files do not exist"), std::string::npos) << run.warnings.front();

  // None there: refused naming the field; a wrong detector size: refused naming the image.
  CircularImportRequest none = good;
  none.files = {(dir / "missing_%d.tif").string()};
  none.out = dir / "none.json";
  try {
    run_import(none);
    ADD_FAILURE() << "a scan without images was imported";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("CircularImportRequest.files: none of the 3 projection files exists"), std::string::npos)
        << e.what();
  }
  CircularImportRequest wrong = good;
  wrong.detector = std::array<int, 2>{30, 40};
  wrong.out = dir / "wrong.json";
  EXPECT_THROW(run_import(wrong), InputError);

  // The scan onto its own first image: refused before anything is written, the image unchanged.
  const fs::path image = dir / "proj_0.tif";
  const std::string before = contents(image);
  CircularImportRequest onto = good;
  onto.out = image;
  onto.field_names = [](const std::string& f) { return "--" + f; };
  try {
    run_import(onto);
    ADD_FAILURE() << "an import wrote over its input";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--out: would overwrite the input --files: projection 0"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(contents(image), before);
  for (const char* name : {"none.json", "wrong.json", "none.matrices.json", "wrong.matrices.json", "proj_0.matrices.json"})
    EXPECT_FALSE(fs::exists(dir / name)) << name;
}

}  // namespace
}  // namespace ctk
