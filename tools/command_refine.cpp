// ctk refine: close the loop on a scan without fiducials (circular orbits). Reconstructs from half
// of the views, predicts the other half, and accepts the named effects (detector offset and roll,
// axis tilt, magnification, angular blur, beam hardening) that predict held-out views better than
// chance. Writes the report (ctk-diagnosis/1, mode "markerless"), the refined per-view matrices, a
// scan file that uses them, and central slices before and after.
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <optional>

#include "commands.hpp"
#include "ctk/geom/output_set.hpp"
#include "ctk/geom/run_files.hpp"
#include "option_checks.hpp"
#include "ctk/geom/atomic_write.hpp"
#include "ctk/geom/error.hpp"
#include "ctk/geom/nominal_geometry.hpp"
#include "ctk/proj/image_io.hpp"
#include "ctk/recon/conjugate_rays.hpp"
#include "ctk/recon/default_volume.hpp"
#include "ctk/recon/markerless_refinement.hpp"
#include "ctk/recon/measurements.hpp"
#include "measurement_report.hpp"
#include "progress.hpp"

namespace ctk::tools {

namespace {

namespace fs = std::filesystem;

struct RefineOptions {
  fs::path scan, geometry, out;
  double coarsening = 2.0;
  double blur_arc_deg = 0;
  double z_accept = 3.0;
  std::vector<std::string> effects;
};

fs::path beside(const fs::path& out, const std::string& suffix) { return out.parent_path() / (out.stem().string() + suffix); }

void write_central_slice(const Volume& x, float high, const fs::path& file) {
  write_slice_png(x, 2, x.layout.size[2] / 2, 0.0f, high, file);
}

// What the final model leaves fixed on the detector: each pixel's mean held-out residual over its
// standard error, grey 0 at mid-grey, black at -10 and white at +10 or beyond (rows left out of
// the costs at 0). A one-row detector is drawn as a band 48 rows high.
void write_pattern_picture(const DetectorPattern& p, const fs::path& file) {
  const int height = p.rows == 1 ? 48 : p.rows;
  Volume z(VolumeLayout::centred({p.cols, height, 1}, Eigen::Vector3d::Ones()));
  for (int row = 0; row < height; ++row)
    for (int c = 0; c < p.cols; ++c) {
      const std::size_t i =
          static_cast<std::size_t>(p.rows == 1 ? 0 : row) * static_cast<std::size_t>(p.cols) + static_cast<std::size_t>(c);
      const double se = p.standard_error[i];
      z.at(c, row, 0) =
          p.used[i] && se > 0 && std::isfinite(se) ? static_cast<float>(std::clamp(p.mean[i] / se, -10.0, 10.0)) : 0.0f;
    }
  write_slice_png(z, 2, 0, -10.0f, 10.0f, file);
}

// The axis' column from the data alone (conjugate rays of the row through the principal point):
// an estimate that does not rest on the yardstick. Full circles at equal steps only; otherwise
// `why_not` says why there is none.
std::optional<ConjugateRayEstimate> conjugate_rays(const Measurements& m, const ConsistencyProbe& probe,
                                                   const ScanDescription& scan, std::string& why_not) {
  const Eigen::Vector2d pp = probe.nominal_principal_point();
  try {
    const FanSinogram s = row_sinogram(m.line_integrals, probe.orbit(), scan.detector, pp.y(), scan.source_to_detector_mm);
    return conjugate_ray_u0(s, pp.x(), 30);
  } catch (const std::invalid_argument& e) {
    why_not = e.what();
    return std::nullopt;
  }
}

nlohmann::json cross_check_json(const std::optional<ConjugateRayEstimate>& e, const std::string& why_not, double loop_u0) {
  if (!e) return {{"method", "conjugate rays"}, {"note", "not available: " + why_not}};
  return {{"method", "conjugate rays: each line measured half a turn apart must agree"},
          {"u0_px", e->u0_px},
          {"uncertainty_px", e->standard_error_px},
          {"rms_mismatch", e->rms_mismatch},
          {"rms_mismatch_other_sense", e->rms_mismatch_other_sense},
          {"loop_u0_px", loop_u0},
          {"difference_px", e->u0_px - loop_u0}};
}

void run_refine(const RefineOptions& o) {
  const auto start = std::chrono::steady_clock::now();
  const ScanDescription scan = read_scan(o.scan);
  RunFiles files;
  require_projection_files(scan, o.scan.string(), "projections.count");
  files.scan("--scan", o.scan, scan);
  files.input("--geometry", o.geometry);
  files.output("--out", o.out);
  for (const char* suffix : {".geometry.json", ".scan.json", ".before.png", ".after.png", ".pattern.png", ".pixel-offsets.tif"})
    files.output(std::string("beside --out: ") + suffix, beside(o.out, suffix));
  files.check();
  OutputSet outputs;  // published together, after the last is written
  for (const auto& w : scan.warnings) std::cerr << "warning: " << w << "\n";
  Geometry geometry = o.geometry.empty() ? nominal_geometry(scan) : read_geometry(o.geometry);
  Progress reading("reading projections", "views");
  const Measurements m = load_measurements(scan, geometry, {false}, std::ref(reading));
  if (m.clamped_pixels > 0) std::cout << "clamped " << m.clamped_pixels << " pixels\n";
  report_masked_and_left_out(m, o.geometry.empty() ? o.scan : o.geometry);

  // Sharpness and pictures need only the central axial slice at full resolution. The coarse grid
  // reaches 20 % beyond the detector's field along the axis, so the cone's edge rays stay inside
  // it and a vertical detector shift is not mistaken for a better fit of a truncated object.
  VolumeLayout fine = default_volume_layout(scan, m.matrices);
  fine = VolumeLayout::centred({fine.size[0], fine.size[1], 1}, fine.voxel_mm);
  VolumeLayout coarse = default_volume_layout(scan, m.matrices, 0, o.coarsening);
  // A one-row (fan-beam) detector sees one slice, in the orbit's plane: the grid is that slice.
  const int coarse_slices = scan.detector.rows == 1 ? 1 : static_cast<int>(std::ceil(1.2 * coarse.size[2]));
  coarse = VolumeLayout::centred({coarse.size[0], coarse.size[1], coarse_slices}, coarse.voxel_mm);
  std::cout << "held-out predictions on " << coarse.size[0] << " x " << coarse.size[1] << " x " << coarse.size[2] << " voxels of "
            << coarse.voxel_mm.x() << " mm; sharpness on " << fine.size[0] << " x " << fine.size[1] << " x " << fine.size[2]
            << "\n";
  const ConsistencyProbe probe(m.line_integrals, m.matrices, scan.detector, coarse, interleaved_split(m.line_integrals.views));

  RefinementOptions options;
  options.z_accept = o.z_accept;
  options.nominal_blur_arc_deg = o.blur_arc_deg;
  if (!o.effects.empty()) options.candidates = o.effects;
  auto log = [&](const std::string& line) {
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::cout << "[" << static_cast<int>(t) << " s] " << line << std::endl;
  };
  std::string why_not;
  const std::optional<ConjugateRayEstimate> conjugate = conjugate_rays(m, probe, scan, why_not);
  if (conjugate) {
    log("conjugate rays put the axis at column " + std::to_string(conjugate->u0_px) + " +- " +
        std::to_string(conjugate->standard_error_px) + " px: the detector offset's scan starts there");
    options.knob_starts["u0_px"] = conjugate->u0_px;
  }
  const RefinementResult r = refine_markerless(probe, fine, options, log);
  const double loop_u0 = probe.nominal_principal_point().x() + r.geometry.du_px;
  const nlohmann::json cross_check = cross_check_json(conjugate, why_not, loop_u0);
  if (conjugate)
    std::cout << "cross-check: conjugate rays " << conjugate->u0_px << " +- " << conjugate->standard_error_px << " px, the loop "
              << loop_u0 << " px (difference " << conjugate->u0_px - loop_u0 << " px)\n";

  // The refined matrices replace the ok views' matrices; other views stay as they were.
  const std::vector<ProjectionMatrix> refined = apply_global_geometry(r.geometry, m.matrices, probe.orbit());
  for (std::size_t i = 0; i < m.view_indices.size(); ++i) {
    GeometryView& v = geometry.views[static_cast<std::size_t>(m.view_indices[i])];
    v.P = refined[i];
    v.rms_px.reset();
  }
  const fs::path geometry_file = beside(o.out, ".geometry.json"), scan_file = beside(o.out, ".scan.json");
  write_geometry(geometry, geometry_file);
  ScanDescription corrected = scan;
  corrected.panda.reset();
  corrected.matrices = MatricesPoseSource{fs::absolute(geometry_file).lexically_proximate(scan.folder).string(), geometry};
  write_scan(corrected, scan_file);

  nlohmann::json report = refinement_to_json(r);
  report["scan"] = o.scan.string();
  report["corrected_geometry"] = geometry_file.string();
  report["corrected_scan"] = scan_file.string();
  report["cross_check"] = cross_check;
  nlohmann::json lacks = nlohmann::json::array();
  if (r.model.blur_arc_rad > 0) lacks.push_back("angular_blur");
  if (r.model.hardening_c2 != 0) lacks.push_back("beam_hardening");
  if (!r.model.pixel_offset.empty())
    lacks.push_back("pixel offsets (pixel_gain / column_gain): in " + beside(o.out, ".pixel-offsets.tif").string());
  if (!lacks.empty()) report["corrected_scan_lacks"] = lacks;
  report["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  write_text_atomically(o.out, report.dump(2) + "\n");

  const float high = preview_ceiling(r.volume_before);  // one grey scale for both pictures
  write_central_slice(r.volume_before, high, beside(o.out, ".before.png"));
  write_central_slice(r.volume_after, high, beside(o.out, ".after.png"));
  write_pattern_picture(r.residual_pattern, beside(o.out, ".pattern.png"));
  if (!r.model.pixel_offset.empty())
    write_image_float(Image{scan.detector.cols, scan.detector.rows, r.model.pixel_offset}, beside(o.out, ".pixel-offsets.tif"));

  outputs.publish();
  std::cout << "held-out projection RMS " << r.heldout_rms_before << " -> " << r.heldout_rms_after << "; sharpness "
            << r.sharpness_before << " -> " << r.sharpness_after << " per mm\n";
  for (const auto& e : r.effects)
    if (e.accepted) std::cout << "accepted " << e.name << " " << e.parameters.dump() << " +- " << e.uncertainty.dump() << "\n";
  std::cout << "report " << o.out.string() << ", refined matrices " << geometry_file.string() << ", scan " << scan_file.string()
            << ", slices " << beside(o.out, ".before.png").string() << " / .after.png, what is left on the detector "
            << beside(o.out, ".pattern.png").string() << "\n";
}

}  // namespace

void register_refine(CLI::App& app) {
  auto o = std::make_shared<RefineOptions>();
  CLI::App* cmd = app.add_subcommand(
      "refine", "Markerless loop for circular scans: find and fit the effects the geometry lacks, judged on held-out views");
  cmd->add_option("--scan", o->scan, "scan.json (ctk-scan/1)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--geometry", o->geometry, "Per-view matrices to start from (default: the scan's nominal geometry)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", o->out, "Report (ctk-diagnosis/1); beside it <stem>.geometry.json, <stem>.scan.json, slices")
      ->required();
  cmd->add_option("--coarsening", o->coarsening, "Voxel of the held-out predictions, in pixels seen at the axis")
      ->check(CLI::Range(1.0, 8.0))
      ->capture_default_str();
  cmd->add_option("--blur-arc", o->blur_arc_deg,
                  "Arc of rotation each view is known to integrate, degrees (sets the blur scan's step)")
      ->check(non_negative_number);
  cmd->add_option("--z", o->z_accept, "Acceptance: held-out improvement in standard errors")
      ->check(positive_number)
      ->capture_default_str();
  cmd->add_option("--effects", o->effects, "Candidates (default: all)")
      ->check(CLI::IsMember({"detector_offset", "detector_roll", "axis_tilt", "magnification", "angular_blur", "beam_hardening",
                             "pixel_gain", "column_gain"}));
  cmd->callback([o] { run_refine(*o); });
}

}  // namespace ctk::tools
