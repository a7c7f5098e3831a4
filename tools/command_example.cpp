// ctk example: writes the built-in example scan description (robot setup, helix holder, a
// joint-7 orbit) so every other command has something real to run on.
#include <filesystem>
#include <iostream>

#include "commands.hpp"
#include "ctk/geom/panda_setup.hpp"
#include "ctk/geom/scan.hpp"

namespace ctk::tools {

namespace {

struct ExampleOptions {
  std::filesystem::path out = "example";
  int views = 90;
  int cols = 360, rows = 360;
  double pitch_mm = 1.2;
  double sdd_mm = 2150.0, sod_mm = 1360.0;
};

void run_example(const ExampleOptions& o) {
  const Detector detector{o.cols, o.rows, o.pitch_mm, o.pitch_mm};
  const PandaSetup setup = reference_panda_setup(detector, o.sdd_mm, o.sod_mm);

  ScanDescription scan;
  scan.folder = o.out;
  scan.detector = detector;
  scan.principal_point_px = setup.principal_point_px;
  scan.source_to_detector_mm = o.sdd_mm;
  scan.projections.files_pattern = "projections/proj_%04d.exr";
  scan.projections.count = o.views;
  scan.projections.kind = ProjectionKind::line_integrals;
  PandaPoseSource panda;
  panda.joints_csv = "joints.csv";
  panda.T_camera_base = setup.T_camera_base;
  panda.T_flange_holder = setup.T_flange_holder;
  const auto orbit = joint7_orbit(setup, o.views);
  for (int v = 0; v < o.views; ++v) panda.joints.add(v, orbit[static_cast<std::size_t>(v)]);
  scan.panda = panda;
  scan.holder = reference_helix_holder();

  std::filesystem::create_directories(o.out);
  scan.panda->joints.write(o.out / "joints.csv");
  write_scan(scan, o.out / "scan.json");
  std::cout << "example scan written to " << (o.out / "scan.json").string() << ": " << o.views << " views, "
            << o.cols << " x " << o.rows << " px at " << o.pitch_mm << " mm, SOD " << o.sod_mm << " mm, SDD "
            << o.sdd_mm << " mm, joint-7 orbit over 332 deg\n";
}

}  // namespace

void register_example(CLI::App& app) {
  auto options = std::make_shared<ExampleOptions>();
  CLI::App* cmd = app.add_subcommand("example", "Write the built-in example scan description (robot setup, helix holder, joints)");
  cmd->add_option("--out", options->out, "Folder to write scan.json and joints.csv into")->capture_default_str();
  cmd->add_option("--views", options->views, "Number of views")->capture_default_str()->check(CLI::Range(1, 100000));
  cmd->add_option("--cols", options->cols, "Detector columns")->capture_default_str()->check(CLI::Range(1, 100000));
  cmd->add_option("--rows", options->rows, "Detector rows")->capture_default_str()->check(CLI::Range(1, 100000));
  cmd->add_option("--pitch", options->pitch_mm, "Pixel pitch (mm)")->capture_default_str()->check(CLI::PositiveNumber);
  cmd->add_option("--sdd", options->sdd_mm, "Source-to-detector distance (mm)")->capture_default_str()->check(CLI::PositiveNumber);
  cmd->add_option("--sod", options->sod_mm, "Source-to-isocentre distance (mm)")->capture_default_str()->check(CLI::PositiveNumber);
  cmd->callback([options] { run_example(*options); });
}

}  // namespace ctk::tools
