// Reading scan.json and joints.csv: valid files round-trip; every kind of bad input is a clear
// InputError that names the file and the key (or line).
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <functional>

#include "../test_support.hpp"
#include "ctk/geom/astra.hpp"
#include "ctk/geom/detector_binning.hpp"
#include "ctk/geom/holder_file.hpp"
#include "ctk/geom/nominal_geometry.hpp"
#include "ctk/geom/panda_setup.hpp"
#include "ctk/geom/scan.hpp"

namespace ctk {
namespace {

// A valid robot scan of `views` views in `dir`; returns the path of scan.json.
std::filesystem::path write_valid_scan(const std::filesystem::path& dir, int views = 12) {
  const PandaSetup setup = reference_panda_setup({240, 200, 1.2, 1.2}, 2150, 1360);
  ScanDescription scan;
  scan.folder = dir;
  scan.detector = setup.detector;
  scan.principal_point_px = setup.principal_point_px;
  scan.source_to_detector_mm = setup.source_to_detector_mm;
  scan.projections.files_pattern = "proj_%04d.tif";
  scan.projections.count = views;
  scan.projections.kind = ProjectionKind::line_integrals;
  PandaPoseSource panda;
  panda.joints_csv = "joints.csv";
  panda.T_camera_base = setup.T_camera_base;
  panda.T_flange_holder = setup.T_flange_holder;
  const auto orbit = joint7_orbit(setup, views);
  for (int v = 0; v < views; ++v) panda.joints.add(v, orbit[static_cast<std::size_t>(v)]);
  scan.panda = panda;
  scan.holder = reference_helix_holder();
  panda.joints.write(dir / "joints.csv");
  write_scan(scan, dir / "scan.json");
  return dir / "scan.json";
}

// Rewrites scan.json after `edit` and expects read_scan to fail naming `key` in its message.
template <typename Edit>
void expect_error_naming(const std::filesystem::path& file, Edit edit, const std::string& key) {
  nlohmann::json j = read_json_file(file);
  edit(j);
  testing::write_text(file, j.dump(2));
  try {
    read_scan(file);
    FAIL() << "no error for a scan file that should be rejected (" << key << ")";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
  }
}

TEST(ScanFile, ValidFileRoundTrips) {
  const auto file = write_valid_scan(testing::scratch_dir());
  const ScanDescription scan = read_scan(file);
  EXPECT_TRUE(scan.warnings.empty());
  EXPECT_EQ(scan.projections.count, 12);
  EXPECT_EQ(scan.projections.file_name(7), "proj_0007.tif");
  EXPECT_EQ(scan.projection_path(7), file.parent_path() / "proj_0007.tif");
  ASSERT_TRUE(scan.panda);
  EXPECT_EQ(scan.panda->joints.rows().size(), 12u);
  ASSERT_TRUE(scan.holder);
  EXPECT_EQ(scan.holder->spheres_mm.size(), 50u);
  EXPECT_EQ(scan_to_json(scan), read_json_file(file));
}

TEST(ScanFile, MissingKeyIsNamed) {
  const auto file = write_valid_scan(testing::scratch_dir());
  expect_error_naming(
      file, [](nlohmann::json& j) { j["detector"].erase("rows"); }, "detector.rows");
}

TEST(ScanFile, WrongTypeIsNamed) {
  const auto file = write_valid_scan(testing::scratch_dir());
  expect_error_naming(
      file, [](nlohmann::json& j) { j["source_to_detector_mm"] = "2150"; }, "source_to_detector_mm");
  expect_error_naming(
      file, [](nlohmann::json& j) { j["detector"]["pixel_pitch_mm"] = {0.6}; }, "detector.pixel_pitch_mm");
}

// Lengths no CT setup has (they overflow or make the matrices singular downstream) are refused
// where they are read, naming the key; so are positions beyond a kilometre.
TEST(ScanFile, LengthsBeyondAnySetupAreNamed) {
  const auto dir = testing::scratch_dir();
  const auto file = [&] { return write_valid_scan(dir); };  // each edit on a valid file
  expect_error_naming(
      file(), [](nlohmann::json& j) { j["source_to_detector_mm"] = 1e-300; }, "source_to_detector_mm");
  expect_error_naming(
      file(),
      [](nlohmann::json& j) {
        j["detector"]["pixel_pitch_mm"] = {1e300, 0.6};
      },
      "detector.pixel_pitch_mm[0]");
  expect_error_naming(
      file(), [](nlohmann::json& j) { j["holder"]["sphere_diameter_mm"] = 1e-9; }, "holder.sphere_diameter_mm");
  expect_error_naming(
      file(),
      [](nlohmann::json& j) {
        j["pose_source"]["T_camera_base"]["t_mm"] = {0, 1e300, 0};
      },
      "pose_source.T_camera_base.t_mm");
  expect_error_naming(
      file(),
      [](nlohmann::json& j) {
        j["holder"]["spheres_mm"][3] = {0, 0, -2e6};
      },
      "holder.spheres_mm[3]");
}

// A declared count that outnumbers the files on disk two to one is refused before any list of
// views is built; a few missing files are left to each view's rejection.
TEST(ScanFile, ACountThatOutnumbersItsFilesIsRefused) {
  const auto dir = testing::scratch_dir();
  const auto file = write_valid_scan(dir, 12);
  for (int v = 0; v < 10; ++v)
    testing::write_text(dir / ("proj_" + std::string(v < 10 ? "000" : "00") + std::to_string(v) + ".tif"), "x");
  const ScanDescription scan = read_scan(file);
  const ProjectionCensus census = require_projection_files(scan, file.string(), "projections.count");
  EXPECT_EQ(census.missing, 2);
  EXPECT_EQ(census.first_missing.filename(), "proj_0010.tif");
  nlohmann::json j = read_json_file(file);
  j["projections"]["count"] = 1000000;
  testing::write_text(file, j.dump(2));
  try {
    require_projection_files(read_scan(file), file.string(), "projections.count");
    FAIL() << "a count of a million over ten files was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("999990 of the 1000000 projection files do not exist"), std::string::npos) << e.what();
  }
}

// Writes `text` as scan.json and returns read_scan's error message ("" if it was accepted).
std::string error_reading(const std::filesystem::path& file, const std::string& text) {
  testing::write_text(file, text);
  try {
    read_scan(file);
  } catch (const InputError& e) {
    return e.what();
  }
  return {};
}

TEST(ScanFile, NaNIsNamed) {
  const auto dir = testing::scratch_dir();
  const auto file = write_valid_scan(dir);
  // NaN is not JSON (but Python's json module writes it, and -Infinity): the error names the
  // line and key, and says why.
  const std::string valid = read_json_file(file).dump(2);
  const std::string key = "\"source_to_detector_mm\": ";
  const auto at = valid.find(key) + key.size();
  const auto with = [&](const std::string& literal) {
    return std::string(valid).replace(at, valid.find_first_of(",\n}", at) - at, literal);
  };
  for (const std::string literal : {"NaN", "-Infinity"}) {
    const std::string what = error_reading(file, with(literal));
    ASSERT_FALSE(what.empty()) << literal << " accepted";
    EXPECT_NE(what.find("source_to_detector_mm"), std::string::npos) << what;
    EXPECT_NE(what.find("line"), std::string::npos) << what;
    EXPECT_NE(what.find("NaN and Infinity are not JSON numbers"), std::string::npos) << what;
  }
  // An infinite value that JSON does parse (1e999) is rejected too.
  EXPECT_FALSE(error_reading(file, with("1e999")).empty());
}

// A file cut short (a copy interrupted) is named with where it ends, and not blamed on NaN.
TEST(ScanFile, TruncatedFileIsNamedWithoutBlamingNaN) {
  const auto file = write_valid_scan(testing::scratch_dir());
  const std::string text = read_json_file(file).dump(2);
  const std::string what = error_reading(file, text.substr(0, text.size() / 2));
  ASSERT_FALSE(what.empty()) << "a truncated file accepted";
  EXPECT_NE(what.find("not valid JSON"), std::string::npos) << what;
  EXPECT_NE(what.find("line"), std::string::npos) << what;
  EXPECT_EQ(what.find("NaN and Infinity"), std::string::npos) << what;
}

// A pattern of tens of thousands of characters is checked without recursion (std::regex
// overflowed the stack on one), accepted when it is a pattern and refused naming the key when not.
TEST(ScanFile, LongFilePatternsAreCheckedWithoutCrashing) {
  const auto dir = testing::scratch_dir();
  const auto file = write_valid_scan(dir);
  expect_error_naming(
      file, [](nlohmann::json& j) { j["projections"]["files"] = std::string(30000, 'x') + "%d_%d.tif"; }, "projections.files");
  expect_error_naming(
      file, [](nlohmann::json& j) { j["projections"]["files"] = std::string(30000, 'x') + ".tif"; }, "projections.files");
  expect_error_naming(
      file, [](nlohmann::json& j) { j["projections"]["files"] = "proj_%4.tif"; }, "projections.files");
}

// Readers open only regular files: a pipe named as a scan, a joint log or a cone_vec file is
// refused at once (it would wait for a writer forever), and so is a folder.
TEST(ScanFile, OnlyRegularFilesAreRead) {
  const auto dir = testing::scratch_dir();
  ASSERT_EQ(::mkfifo((dir / "pipe").c_str(), 0600), 0);
  for (const auto& read : std::vector<std::function<void(const std::filesystem::path&)>>{
           [](const std::filesystem::path& f) { read_json_file(f); },
           [](const std::filesystem::path& f) { JointLog::read(f, 3); },
           [](const std::filesystem::path& f) { read_cone_vecs(f); }})
    for (const auto& f : {dir / "pipe", dir}) {
      try {
        read(f);
        ADD_FAILURE() << f << " was read";
      } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("not a regular file"), std::string::npos) << e.what();
      }
    }
}

TEST(ScanFile, RotationMustBeARotation) {
  const auto file = write_valid_scan(testing::scratch_dir());
  expect_error_naming(
      file, [](nlohmann::json& j) { j["pose_source"]["T_camera_base"]["R"][0][0] = 2.0; }, "pose_source.T_camera_base.R");
}

TEST(ScanFile, UnreadablePathIsNamed) {
  const auto file = write_valid_scan(testing::scratch_dir());
  expect_error_naming(
      file, [](nlohmann::json& j) { j["pose_source"]["joints_csv"] = "nowhere.csv"; }, "pose_source.joints_csv");
  expect_error_naming(
      file,
      [](nlohmann::json& j) {
        j["projections"]["kind"] = "counts";
        j["projections"]["flat"] = "flat.tif";
        j["projections"]["dark"] = "dark.tif";
      },
      "projections.flat");
}

TEST(ScanFile, CountsNeedFlatAndDark) {
  const auto file = write_valid_scan(testing::scratch_dir());
  expect_error_naming(
      file, [](nlohmann::json& j) { j["projections"]["kind"] = "counts"; }, "projections.flat");
  expect_error_naming(
      file, [](nlohmann::json& j) { j["projections"]["kind"] = "photons"; }, "projections.kind");
}

TEST(ScanFile, ProjectionCountMustMatchJointRows) {
  const auto file = write_valid_scan(testing::scratch_dir(), 12);
  // Fewer projections than the log has rows: the log names a view the scan does not have.
  try {
    nlohmann::json j = read_json_file(file);
    j["projections"]["count"] = 10;
    testing::write_text(file, j.dump(2));
    read_scan(file);
    FAIL() << "count mismatch accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("joints.csv"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("projections.count"), std::string::npos) << e.what();
  }
}

TEST(ScanFile, AbsentJointRowsAreSkippedViewsNotErrors) {
  const auto dir = testing::scratch_dir();
  const auto file = write_valid_scan(dir, 12);
  nlohmann::json j = read_json_file(file);
  j["projections"]["count"] = 14;  // views 12 and 13 were not reached
  testing::write_text(file, j.dump(2));
  const auto scan = read_scan(file);
  const auto g = nominal_geometry(scan);
  ASSERT_EQ(g.views.size(), 14u);
  EXPECT_EQ(g.views[13].status, ViewStatus::skipped);
  EXPECT_NE(g.views[13].reason.find("no joints row"), std::string::npos);
  EXPECT_EQ(g.ok_views().size(), 12u);
}

// The extensions a corrected scan writes: radial distortion and source drift round-trip, and a
// malformed one is an error naming its key; a scan without them means what it always meant.
TEST(ScanFile, DistortionAndDriftExtensions) {
  const auto file = write_valid_scan(testing::scratch_dir());
  ScanDescription scan = read_scan(file);
  EXPECT_FALSE(scan.distortion);
  EXPECT_EQ(scan.source_drift_mm_per_100_views, Eigen::Vector2d::Zero());
  EXPECT_EQ(scan.source_offset_mm(50), Eigen::Vector3d::Zero());
  scan.distortion = RadialDistortion{2e-8, {380, 340}};
  scan.source_drift_mm_per_100_views = {1.0, -0.6};
  write_scan(scan, file);
  const ScanDescription back = read_scan(file);
  EXPECT_TRUE(back.warnings.empty());
  ASSERT_TRUE(back.distortion);
  EXPECT_EQ(back.distortion->k1_per_px2, 2e-8);
  EXPECT_EQ(back.distortion->centre_px, Eigen::Vector2d(380, 340));
  EXPECT_EQ(back.source_offset_mm(50), Eigen::Vector3d(0.5, -0.3, 0.0));
  expect_error_naming(
      file, [](nlohmann::json& j) { j["detector"]["radial_distortion"]["center_px"] = {1.0}; },
      "detector.radial_distortion.center_px");
  write_scan(scan, file);  // each check starts from a valid file
  expect_error_naming(
      file, [](nlohmann::json& j) { j["source_drift_mm_per_100_views"] = "fast"; }, "source_drift_mm_per_100_views");
}

// detector.binning: every pixel address follows the binned detector in memory, the file keeps
// stating the stored images, and a point projects onto the binned pixel that holds it.
TEST(ScanFile, BinningExtension) {
  const auto dir = testing::scratch_dir();
  const auto file = write_valid_scan(dir, 6);
  ScanDescription plain = read_scan(file);
  EXPECT_EQ(plain.binning, 1);
  plain.distortion = RadialDistortion{2e-8, {121.3, 98.7}};
  write_scan(plain, file);
  plain = read_scan(file);
  nlohmann::json j = read_json_file(file);
  j["detector"]["binning"] = 3;
  testing::write_text(dir / "binned.json", j.dump(2));
  const ScanDescription binned = read_scan(dir / "binned.json");
  EXPECT_TRUE(binned.warnings.empty());
  EXPECT_EQ(binned.binning, 3);
  EXPECT_EQ(binned.stored_detector.cols, 240);
  EXPECT_EQ(binned.detector.cols, 80);
  EXPECT_EQ(binned.detector.rows, 66);  // 200 / 3: the last partial row is dropped
  EXPECT_DOUBLE_EQ(binned.detector.pitch_u_mm, 3.6);
  EXPECT_NEAR(binned.principal_point_px.x(), (plain.principal_point_px.x() - 1) / 3, 1e-12);
  EXPECT_NEAR(binned.distortion->k1_per_px2, 2e-8 * 9, 1e-20);
  // The distortion's shift, in binned pixels, is a third of the stored one at the same place.
  const Eigen::Vector2d fine(30, 170), coarse = binned_pixel(fine, 3);
  EXPECT_LT(
      (binned.distortion->measured_from_ideal(coarse) - binned_pixel(plain.distortion->measured_from_ideal(fine), 3)).norm(),
      1e-9);
  const Geometry g = nominal_geometry(plain), gb = nominal_geometry(binned);
  for (const Eigen::Vector3d& X : {Eigen::Vector3d(10, -5, 20), Eigen::Vector3d(-25, 15, -30)})
    for (std::size_t v = 0; v < g.views.size(); ++v)
      EXPECT_LT((gb.views[v].P->project(X) - binned_pixel(g.views[v].P->project(X), 3)).norm(), 1e-6);
  // Written back, the file states what it stated.
  write_scan(binned, dir / "again.json");
  const nlohmann::json again = read_json_file(dir / "again.json");
  EXPECT_EQ(again["detector"]["cols"], 240);
  EXPECT_EQ(again["detector"]["binning"], 3);
  for (int i = 0; i < 2; ++i) {
    EXPECT_NEAR(again["detector"]["principal_point_px"][i].get<double>(), j["detector"]["principal_point_px"][i].get<double>(),
                1e-9);
    EXPECT_NEAR(again["detector"]["radial_distortion"]["center_px"][i].get<double>(),
                j["detector"]["radial_distortion"]["center_px"][i].get<double>(), 1e-9);
  }
  EXPECT_NEAR(again["detector"]["radial_distortion"]["k1_per_px2"].get<double>(), 2e-8, 1e-22);
  // A geometry for the stored pixels is binned for the scan; one for the binned detector is kept.
  write_geometry(g, dir / "stored.json");
  write_geometry(gb, dir / "coarse.json");
  const Geometry from_stored = geometry_or_nominal(binned, dir / "binned.json", dir / "stored.json");
  const Geometry from_coarse = geometry_or_nominal(binned, dir / "binned.json", dir / "coarse.json");
  EXPECT_EQ(from_stored.detector.cols, 80);
  EXPECT_LT(max_abs_difference(*from_stored.views[2].P, *gb.views[2].P), 1e-9);
  EXPECT_LT(max_abs_difference(*from_coarse.views[2].P, *gb.views[2].P), 1e-9);
  expect_error_naming(
      dir / "binned.json", [](nlohmann::json& k) { k["detector"]["binning"] = 0; }, "detector.binning");
  expect_error_naming(
      dir / "binned.json", [](nlohmann::json& k) { k["detector"]["binning"] = 201; }, "detector.binning");
}

// A scan written elsewhere (a corrected scan beside its report) still finds its files.
TEST(ScanFile, RelocatedScanFindsTheSameFiles) {
  const auto dir = testing::scratch_dir();
  const auto file = write_valid_scan(dir, 6);
  nlohmann::json j = read_json_file(file);
  j["projections"]["kind"] = "counts";
  j["projections"]["flat"] = {"flats/f0.tif", "flats/f1.tif"};
  j["projections"]["dark"] = "dark.tif";
  std::filesystem::create_directories(dir / "flats");
  for (const char* f : {"flats/f0.tif", "flats/f1.tif", "dark.tif"}) testing::write_text(dir / f, "");
  testing::write_text(file, j.dump(2));
  const ScanDescription scan = read_scan(file);
  const std::filesystem::path elsewhere = dir / "out" / "deeper" / "corrected.json";
  std::filesystem::create_directories(elsewhere.parent_path());
  write_scan(relocated_scan(scan, elsewhere), elsewhere);
  const ScanDescription moved = read_scan(elsewhere);
  auto same = [](const std::filesystem::path& a, const std::filesystem::path& b) {
    return std::filesystem::weakly_canonical(a) == std::filesystem::weakly_canonical(b);
  };
  EXPECT_TRUE(same(moved.projection_path(4), scan.projection_path(4))) << moved.projection_path(4);
  EXPECT_EQ(moved.projections.files_pattern, "../../proj_%04d.tif");
  EXPECT_TRUE(same(moved.resolve(moved.projections.flat[1]), dir / "flats/f1.tif"));
  EXPECT_TRUE(same(moved.resolve(moved.projections.dark[0]), dir / "dark.tif"));
  EXPECT_TRUE(same(moved.resolve(moved.panda->joints_csv), dir / "joints.csv"));
}

// A holder described once (ctk-holder/1) and named by a scan: read from the file, written back
// as the name while the holder is as filed, spelt out once a workflow changed it, and found from
// a scan written elsewhere.
TEST(ScanFile, HolderFileNamedByTheScan) {
  const auto dir = testing::scratch_dir();
  const auto file = write_valid_scan(dir, 6);
  nlohmann::json holder = holder_to_json(thesis_first_holder());
  holder["format"] = "ctk-holder/1";
  std::filesystem::create_directories(dir / "holders");
  testing::write_text(dir / "holders" / "printed.json", holder.dump(2));
  nlohmann::json j = read_json_file(file);
  j["holder"] = "holders/printed.json";
  testing::write_text(file, j.dump(2));
  ScanDescription scan = read_scan(file);
  ASSERT_TRUE(scan.holder);
  ASSERT_TRUE(scan.holder_file);
  EXPECT_EQ(scan.holder_file->name, "holders/printed.json");
  EXPECT_EQ(scan.holder->spheres_mm.size(), 50u);
  EXPECT_DOUBLE_EQ(scan.holder->sphere_diameter_mm, 0.678);
  EXPECT_EQ(scan_to_json(scan)["holder"], "holders/printed.json");

  const std::filesystem::path elsewhere = dir / "out" / "corrected.json";
  std::filesystem::create_directories(elsewhere.parent_path());
  write_scan(relocated_scan(scan, elsewhere), elsewhere);
  EXPECT_EQ(read_json_file(elsewhere)["holder"], "../holders/printed.json");
  EXPECT_EQ(read_scan(elsewhere).holder->spheres_mm[7], scan.holder->spheres_mm[7]);

  scan.holder->spheres_mm[3].x() += 0.05;  // a diagnosis moved a sphere: the holder is no longer the file's
  const nlohmann::json changed = scan_to_json(scan)["holder"];
  ASSERT_TRUE(changed.is_object());
  EXPECT_DOUBLE_EQ(changed["spheres_mm"][3][0].get<double>(), scan.holder->spheres_mm[3].x());

  j["holder"] = "holders/missing.json";
  testing::write_text(file, j.dump(2));
  EXPECT_THROW(read_scan(file), InputError);
}

// The holder block's two spellings of the centres and of the helix' rise; both, or neither, named.
TEST(HolderFile, CentresOnTheHelixAndItsPitch) {
  const auto dir = testing::scratch_dir();
  const nlohmann::json on_helix = {{"format", "ctk-holder/1"},
                                   {"helix", {{"radius_mm", 19.5}, {"pitch_mm", 24.0}, {"phase_rad", 0.0}}},
                                   {"sphere_diameter_mm", 0.678},
                                   {"spheres_on_helix", {{"count", 50}, {"tau_mm", {-24.0, 24.0}}}},
                                   {"wall", {{"inner_radius_mm", 17.5}, {"outer_radius_mm", 19.5}, {"ends_mm", {-28.0, 28.0}}}}};
  testing::write_text(dir / "h.json", on_helix.dump());
  const Holder read = read_holder_file(dir / "h.json");
  const Holder thesis = thesis_first_holder();
  ASSERT_EQ(read.spheres_mm.size(), thesis.spheres_mm.size());
  for (std::size_t k = 0; k < read.spheres_mm.size(); ++k) EXPECT_LT((read.spheres_mm[k] - thesis.spheres_mm[k]).norm(), 1e-12);
  EXPECT_NEAR(read.helix.rho_rad_per_mm, 2 * M_PI / 24.0, 1e-15);
  EXPECT_EQ(holder_named(dir.string() + "/h.json").spheres_mm.size(), 50u);
  EXPECT_EQ(holder_named("reference").spheres_mm.size(), 50u);
  EXPECT_THROW(holder_named("no-such-holder"), InputError);

  auto refused = [&](const std::function<void(nlohmann::json&)>& spoil, const std::string& key) {
    nlohmann::json j = on_helix;
    spoil(j);
    testing::write_text(dir / "bad.json", j.dump());
    try {
      read_holder_file(dir / "bad.json");
      ADD_FAILURE() << "accepted a holder without a valid " << key;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("bad.json"), std::string::npos) << e.what();
    }
  };
  refused([](nlohmann::json& j) { j["helix"]["rho_rad_per_mm"] = 0.26; }, "helix");
  refused([](nlohmann::json& j) { j["helix"].erase("pitch_mm"); }, "helix");
  refused([](nlohmann::json& j) { j["spheres_mm"] = {{0, 0, 0}}; }, "spheres_mm");
  refused([](nlohmann::json& j) { j["spheres_on_helix"]["count"] = 0; }, "spheres_on_helix.count");
  refused([](nlohmann::json& j) { j["spheres_on_helix"]["tau_mm"] = {24.0, -24.0}; }, "spheres_on_helix.tau_mm");
  refused([](nlohmann::json& j) { j["format"] = "ctk-scan/1"; }, "format");
}

// The origin of a geometry file's matrices is kept, and a matrices scan's nominal geometry is
// what its matrices are.
TEST(GeometryFile, OriginRoundTrips) {
  const auto dir = testing::scratch_dir();
  const ScanDescription scan = read_scan(write_valid_scan(dir, 4));
  Geometry g = nominal_geometry(scan);
  EXPECT_EQ(g.origin, "nominal");
  g.origin = "refined";
  write_geometry(g, dir / "refined.json");
  const Geometry back = read_geometry(dir / "refined.json");
  EXPECT_EQ(back.origin, "refined");
  EXPECT_EQ(back.description(), "refined (" + (dir / "refined.json").string() + ")");
  nlohmann::json j = read_json_file(dir / "scan.json");
  j["pose_source"] = {{"kind", "matrices"}, {"file", "refined.json"}};
  testing::write_text(dir / "scan_refined.json", j.dump(2));
  EXPECT_EQ(nominal_geometry(read_scan(dir / "scan_refined.json")).origin, "refined");
}

TEST(ScanFile, HolderWallExtension) {
  const auto file = write_valid_scan(testing::scratch_dir());
  const ScanDescription scan = read_scan(file);
  ASSERT_TRUE(scan.holder->wall);  // the reference holder declares its tube
  EXPECT_EQ(scan.holder->wall->inner_radius_mm, 25.0);
  EXPECT_EQ(scan.holder->wall->outer_radius_mm, 28.0);
  ASSERT_TRUE(scan.holder->wall->ends_mm);  // and its ends
  EXPECT_EQ(*scan.holder->wall->ends_mm, Eigen::Vector2d(-59, 59));
  expect_error_naming(
      file,
      [](nlohmann::json& j) {
        j["holder"]["wall"]["ends_mm"] = {10.0, 59.0};
      },
      "holder.wall.ends_mm");
  write_scan(scan, file);
  expect_error_naming(
      file,
      [](nlohmann::json& j) {
        j["holder"]["wall"]["ends_mm"] = {59.0, -59.0};
      },
      "holder.wall.ends_mm");
  write_scan(scan, file);
  expect_error_naming(
      file, [](nlohmann::json& j) { j["holder"]["wall"]["outer_radius_mm"] = 20.0; }, "holder.wall.outer_radius_mm");
  write_scan(scan, file);
  expect_error_naming(
      file, [](nlohmann::json& j) { j["holder"]["wall"].erase("inner_radius_mm"); }, "holder.wall.inner_radius_mm");
  write_scan(scan, file);
  // Without the ends the tube is infinitely long; without the key the holder has no wall, as
  // before the extension.
  nlohmann::json j = read_json_file(file);
  j["holder"]["wall"].erase("ends_mm");
  testing::write_text(file, j.dump(2));
  EXPECT_FALSE(read_scan(file).holder->wall->ends_mm);
  j["holder"].erase("wall");
  testing::write_text(file, j.dump(2));
  EXPECT_FALSE(read_scan(file).holder->wall);
}

TEST(ScanFile, UnknownKeysWarn) {
  const auto file = write_valid_scan(testing::scratch_dir());
  nlohmann::json j = read_json_file(file);
  j["operator"] = "someone";
  testing::write_text(file, j.dump(2));
  const auto scan = read_scan(file);
  ASSERT_EQ(scan.warnings.size(), 1u);
  EXPECT_NE(scan.warnings[0].find("operator"), std::string::npos);
}

TEST(JointLog, BadRowsAreNamedByLine) {
  const auto dir = testing::scratch_dir();
  const auto file = dir / "joints.csv";
  testing::write_text(file, "view,q1,q2,q3,q4,q5,q6,q7\n0,0,0,0,-1,0,1,0\n1,0,0,zero,-1,0,1,0\n");
  try {
    JointLog::read(file, 5);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("line 3, column q3"), std::string::npos) << e.what();
  }
  testing::write_text(file, "view,q1,q2,q3,q4,q5,q6,q7\n0,0,0,0,-1,0,1,nan\n");
  EXPECT_THROW(JointLog::read(file, 5), InputError);
  testing::write_text(file, "view,q1,q2,q3,q4,q5,q6,q7\n0,0,0,0,-1,0,1,0\n0,0,0,0,-1,0,1,0\n");
  EXPECT_THROW(JointLog::read(file, 5), InputError);  // duplicate view
  testing::write_text(file, "view,a,b\n");
  EXPECT_THROW(JointLog::read(file, 5), InputError);  // header
}

TEST(JointLog, OutOfLimitRowIsFlaggedAndSkipped) {
  const auto dir = testing::scratch_dir();
  const auto file = write_valid_scan(dir, 3);
  testing::write_text(dir / "joints.csv",
                      "view,q1,q2,q3,q4,q5,q6,q7\n0,0,-0.78,0,-2.35,0,1.57,0.78\n1,0,-0.78,0,0.5,0,1.57,0.78\n");
  const auto scan = read_scan(file);
  const auto g = nominal_geometry(scan);
  EXPECT_EQ(g.views[0].status, ViewStatus::ok);
  EXPECT_EQ(g.views[1].status, ViewStatus::skipped);
  EXPECT_NE(g.views[1].reason.find("q4"), std::string::npos) << g.views[1].reason;
}

TEST(GeometryFile, RoundTripAndMatricesPoseSource) {
  const auto dir = testing::scratch_dir();
  const auto scan = read_scan(write_valid_scan(dir, 6));
  const Geometry g = nominal_geometry(scan);
  write_geometry(g, dir / "geometry.json");
  const Geometry back = read_geometry(dir / "geometry.json");
  ASSERT_EQ(back.views.size(), g.views.size());
  for (std::size_t i = 0; i < g.views.size(); ++i) EXPECT_LT(max_abs_difference(*back.views[i].P, *g.views[i].P), 1e-12);

  // The same views as a "matrices" pose source give the same nominal geometry.
  nlohmann::json j = read_json_file(dir / "scan.json");
  j["pose_source"] = {{"kind", "matrices"}, {"file", "geometry.json"}};
  testing::write_text(dir / "scan_matrices.json", j.dump(2));
  const auto g2 = nominal_geometry(read_scan(dir / "scan_matrices.json"));
  for (std::size_t i = 0; i < g.views.size(); ++i) EXPECT_LT(max_abs_difference(*g2.views[i].P, *g.views[i].P), 1e-12);

  // An ok view without P is an error naming the key.
  nlohmann::json bad = read_json_file(dir / "geometry.json");
  bad["views"][2].erase("P");
  testing::write_text(dir / "bad.json", bad.dump());
  try {
    read_geometry(dir / "bad.json");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("views[2].P"), std::string::npos) << e.what();
  }
}

TEST(ReferenceSetup, HolderCentreSitsAtTheIsocentreOnTheBeam) {
  const PandaSetup setup = reference_panda_setup({720, 720, 0.6, 0.6}, 2150, 1360);
  for (const auto& q : joint7_orbit(setup, 9)) {
    const Rigid T = setup.T_camera_base * panda::forward_kinematics(q) * setup.T_flange_holder;
    EXPECT_LT((T.translation() - Eigen::Vector3d(0, 0, 1360)).norm(), 1e-9);
    // The holder axis stays perpendicular to the beam while joint 7 turns the holder about it.
    EXPECT_NEAR(T.linear().col(2).z(), 0.0, 1e-12);
  }
}

}  // namespace
}  // namespace ctk
