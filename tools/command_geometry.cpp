// ctk geometry: the nominal per-view geometry a scan file predicts (robot FK through the setup
// frames, or the matrices given), or a calibrated or refined one given with --geometry, written
// as ctk-geometry/1 (and as ASTRA cone_vec rows or RTK geometry XML), with a report.
#include <algorithm>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <stdexcept>

#include "commands.hpp"
#include "ctk/core/error.hpp"
#include "ctk/core/output_set.hpp"
#include "ctk/geom/astra.hpp"
#include "ctk/geom/geometry_summary.hpp"
#include "ctk/geom/nominal_geometry.hpp"
#include "ctk/geom/rtk_geometry.hpp"
#include "ctk/geom/run_files.hpp"

namespace ctk::tools {

namespace {

struct GeometryOptions {
  std::filesystem::path scan, geometry, out = "geometry.json", astra, rtk;
};

void report(const ScanDescription& scan, const Geometry& g) {
  std::vector<double> sod, spheres_visible;
  int skipped = 0;
  for (const auto& v : g.views) {
    if (v.status != ViewStatus::ok) {
      ++skipped;
      std::cout << "  view " << v.index << ": " << to_string(v.status) << " — " << v.reason << "\n";
      continue;
    }
    sod.push_back((v.P->source_position()).norm());
    if (scan.holder) {
      int n = 0;
      for (const auto& s : scan.holder->spheres_mm) n += g.detector.contains(v.P->project(s), 1.0) ? 1 : 0;
      spheres_visible.push_back(n);
    }
  }
  auto range = [](std::vector<double> x) {
    std::sort(x.begin(), x.end());
    std::ostringstream s;
    s << std::fixed << std::setprecision(2) << x.front() << " / " << x[x.size() / 2] << " / " << x.back();
    return s.str();
  };
  std::cout << "views: " << g.views.size() << " (" << g.views.size() - static_cast<std::size_t>(skipped) << " with a pose, "
            << skipped << " skipped)\n";
  if (sod.empty()) return;
  std::cout << "source to holder origin (mm), min / median / max: " << range(sod) << "\n" << to_text(summarize_geometry(g));
  if (!spheres_visible.empty())
    std::cout << "holder spheres projecting onto the detector, min / median / max: " << range(spheres_visible) << " of "
              << scan.holder->spheres_mm.size() << "\n";
}

// The posed views as RTK parameters, under the pixel map that holds the first (all must agree:
// a scan's detector is mirrored in every view or in none); a view RTK's parameters cannot hold is
// named.
std::vector<RtkProjection> rtk_views(const Geometry& g, RtkRows& rows) {
  std::vector<RtkProjection> out;
  bool first = true;
  for (const auto& v : g.views) {
    if (!v.P) continue;
    if (first) rows = rtk_rows_for(*v.P);
    first = false;
    try {
      out.push_back(to_rtk(holder_matrix_in_rtk_frame(*v.P), g.detector, rows));
    } catch (const std::invalid_argument& e) {
      throw InputError(g.source(), "views[" + std::to_string(v.index) + "].P", e.what());
    }
  }
  return out;
}

void run_geometry(const GeometryOptions& o) {
  const ScanDescription scan = read_scan(o.scan);
  RunFiles files;
  files.scan_to_read("--scan", o.scan, scan);
  files.input("--geometry", o.geometry);
  files.output("--out", o.out);
  files.output("--astra", o.astra);
  files.output("--rtk", o.rtk);
  files.check();
  OutputSet outputs;  // published together, after the last is written
  for (const auto& w : scan.warnings) std::cerr << "warning: " << w << "\n";
  const Geometry g = o.geometry.empty() ? nominal_geometry(scan) : read_geometry(o.geometry);
  const std::string origin = o.geometry.empty() ? "nominal geometry of " + o.scan.string() : "geometry of " + o.geometry.string();
  write_geometry(g, o.out);
  std::vector<ConeVec> vecs;
  if (!o.astra.empty()) {
    for (const auto& v : g.views)
      if (v.P) vecs.push_back(to_cone_vec(*v.P, g.detector));
    write_cone_vecs(vecs, o.astra);
  }
  std::vector<RtkProjection> rtk;
  RtkRows rows = RtkRows::flipped;
  if (!o.rtk.empty()) {
    rtk = rtk_views(g, rows);
    write_rtk_geometry(rtk, rows, o.rtk, true);
  }
  outputs.publish();
  std::cout << origin << " written to " << o.out.string() << "\n";
  if (!o.astra.empty())
    std::cout << "ASTRA cone_vec rows (mm) of the " << vecs.size() << " posed views written to " << o.astra.string() << "\n";
  if (!o.rtk.empty())
    std::cout << "RTK geometry of the " << rtk.size() << " posed views written to " << o.rtk.string() << " (pixel map "
              << to_string(rows)
              << (rows == RtkRows::flipped ? ": give RTK the projections flipped vertically" : ": RTK reads the images as stored")
              << ", origin at minus half their extent; the holder's axis on RTK's y: RTK (x, y, z) = holder (x, z, -y); "
                 "docs/formats.md)\n";
  report(scan, g);
}

}  // namespace

void register_geometry(CLI::App& app) {
  auto options = std::make_shared<GeometryOptions>();
  CLI::App* cmd =
      app.add_subcommand("geometry", "Nominal per-view geometry of a scan (robot FK or given matrices), with a report");
  cmd->add_option("--scan", options->scan, "scan.json (ctk-scan/1)")->required();
  cmd->add_option("--out", options->out, "geometry file to write (ctk-geometry/1)")->capture_default_str();
  cmd->add_option("--geometry", options->geometry,
                  "a calibrated or refined geometry (ctk-geometry/1) to write instead of the nominal one")
      ->check(CLI::ExistingFile);
  cmd->add_option("--astra", options->astra, "also write ASTRA cone_vec rows (mm) to this file");
  cmd->add_option("--rtk", options->rtk, "also write RTK's geometry XML (RTKThreeDCircularGeometry, version 3) to this file");
  cmd->callback([options] { run_geometry(*options); });
}

}  // namespace ctk::tools
