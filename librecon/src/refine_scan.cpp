#include "ctk/recon/refine_scan.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "ctk/core/error.hpp"
#include "ctk/measure/measurements.hpp"
#include "ctk/recon/default_volume.hpp"
#include "ctk/recon/disjoint_parts.hpp"
#include "ctk/recon/repeat_exposure.hpp"

namespace ctk {

namespace {

// The axis' column from the data alone (conjugate rays of the row through the principal point):
// an estimate that does not rest on the yardstick; and, where the scan ends with a new exposure
// at its first angle, whether the object moved. Full circles at equal steps only; otherwise
// `s.conjugate_why_not` says why there is none.
void data_alone_checks(const Measurements& m, const ConsistencyProbe& probe, const ScanDescription& scan, RefineScanSummary& s) {
  const Eigen::Vector2d pp = probe.nominal_principal_point();
  try {
    const FanSinogram sinogram = row_sinogram(m.line_integrals, probe.orbit(), scan.detector, pp.y(), scan.source_to_detector_mm);
    s.repeat = compare_repeat_exposure(sinogram);
    s.conjugate = conjugate_ray_u0(sinogram, pp.x(), 30);
  } catch (const std::invalid_argument& e) {
    s.conjugate_why_not = e.what();
  }
}

}  // namespace

void RefineScanOptions::validate() const {
  require_option(coarsening >= 1 && coarsening <= 8, "RefineScanOptions.coarsening", "a number in [1, 8]", coarsening);
  require_option(blur_arc_deg >= 0 && std::isfinite(blur_arc_deg), "RefineScanOptions.blur_arc_deg",
                 "a finite number of 0 or more", blur_arc_deg);
  require_option(z_accept > 0 && std::isfinite(z_accept), "RefineScanOptions.z_accept", "a finite positive number", z_accept);
}

RefineScanSummary refine_scan(const ScanDescription& scan, Geometry geometry, const RefineScanOptions& o,
                              const std::function<void(const std::string&)>& log, const std::function<void(int, int)>& reading) {
  o.validate();
  RefinementOptions options;
  options.z_accept = o.z_accept;
  options.nominal_blur_arc_deg = o.blur_arc_deg;
  if (!o.effects.empty()) options.candidates = o.effects;
  options.validate();
  const auto start = std::chrono::steady_clock::now();
  const auto say = [&](const std::string& line) {
    if (log) log(line);
  };

  const Measurements m = load_measurements(scan, geometry, {false}, reading);
  require_views_left(m, geometry.source());
  // Sharpness and pictures need only the central axial slice at full resolution. The coarse grid
  // reaches 20 % beyond the detector's field along the axis, so the cone's edge rays stay inside
  // it and a vertical detector shift is not mistaken for a better fit of a truncated object.
  VolumeLayout fine = default_volume_layout(scan, m.matrices);
  fine = VolumeLayout::centred({fine.size[0], fine.size[1], 1}, fine.voxel_mm);
  VolumeLayout coarse = default_volume_layout(scan, m.matrices, 0, o.coarsening);
  // A one-row (fan-beam) detector sees one slice, in the orbit's plane: the grid is that slice.
  const int coarse_slices = scan.detector.rows == 1 ? 1 : static_cast<int>(std::ceil(1.2 * coarse.size[2]));
  coarse = VolumeLayout::centred({coarse.size[0], coarse.size[1], coarse_slices}, coarse.voxel_mm);
  std::ostringstream grids;
  grids << "held-out predictions on " << coarse.size[0] << " x " << coarse.size[1] << " x " << coarse.size[2] << " voxels of "
        << coarse.voxel_mm.x() << " mm; sharpness on " << fine.size[0] << " x " << fine.size[1] << " x " << fine.size[2];
  say(grids.str());
  const ConsistencyProbe probe(m.line_integrals, m.matrices, scan.detector, coarse, interleaved_split(m.line_integrals.views));

  RefineScanSummary s;
  s.clamped_pixels = m.clamped_pixels;
  s.masked_pixels = m.masked_pixels;
  s.left_out = m.left_out;
  data_alone_checks(m, probe, scan, s);
  if (s.repeat) {
    std::ostringstream line;
    line << "views 0 and " << s.repeat->last_view << " (the same angle): shifted " << s.repeat->shift_px << " +- "
         << s.repeat->shift_sigma_px << " px, RMS difference " << s.repeat->rms_difference
         << (s.repeat->moved() ? ": the object moved during the scan" : "");
    say(line.str());
  }
  if (s.conjugate) {
    say("conjugate rays put the axis at column " + std::to_string(s.conjugate->u0_px) + " +- " +
        std::to_string(s.conjugate->standard_error_px) + " px: the detector offset's scan starts there");
    options.knob_starts["u0_px"] = s.conjugate->u0_px;
  }
  s.result = refine_markerless(probe, fine, options, log);

  // The refined matrices replace the ok views' matrices; other views stay as they were.
  const std::vector<ProjectionMatrix> refined = apply_global_geometry(s.result.geometry, m.matrices, probe.orbit());
  for (std::size_t i = 0; i < m.view_indices.size(); ++i) {
    GeometryView& v = geometry.views[static_cast<std::size_t>(m.view_indices[i])];
    v.P = refined[i];
    v.rms_px.reset();
  }
  s.refined = std::move(geometry);
  s.refined.origin = "refined";
  s.refined.file.clear();
  s.loop_u0_px = probe.nominal_principal_point().x() + s.result.geometry.du_px;
  s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return s;
}

double RefineScanSummary::loop_u0_sigma_px(bool covering) const {
  for (const RefinedEffect& e : result.effects)
    if (e.accepted && e.name == "detector_offset" && e.uncertainty.contains("u0_px") && e.uncertainty.at("u0_px").is_number()) {
      if (covering && e.halves_in_time.contains("u0_px")) return e.halves_in_time.at("u0_px").at("uncertainty").get<double>();
      return e.uncertainty.at("u0_px").get<double>();
    }
  return 0;
}

nlohmann::json RefineScanSummary::report() const {
  nlohmann::json r = refinement_to_json(result);
  if (!conjugate) {
    r["cross_check"] = {{"method", "conjugate rays"}, {"note", "not available: " + conjugate_why_not}};
  } else {
    // Two estimates of one column, each with the uncertainty that covers its disjoint parts (the
    // loop's halves in time, the conjugate pairs' two sets of opposite quarter turns). Where they
    // differ by more than those allow, something neither states (the yardstick's own error, a
    // motion both parts share) is at work, and both are scaled by the ratio (the Particle Data
    // Group's scale factor for inconsistent measurements, S = sqrt(chi^2 / (N - 1)), N = 2).
    const double difference = conjugate->u0_px - loop_u0_px;
    const double loop_sigma = loop_u0_sigma_px(true);
    const double quarters_sigma =
        covering_uncertainty(conjugate->u0_quarters_px[0], conjugate->u0_quarters_px[1], conjugate->standard_error_px);
    const double combined = std::hypot(quarters_sigma, loop_sigma);
    const double scale = combined > 0 ? std::max(1.0, std::abs(difference) / combined) : 1.0;
    r["cross_check"] = {{"method", "conjugate rays: each line measured half a turn apart must agree"},
                        {"u0_px", conjugate->u0_px},
                        {"uncertainty_px", conjugate->standard_error_px},
                        {"quarter_turns", disjoint_parts_json(conjugate->u0_quarters_px[0], conjugate->u0_quarters_px[1],
                                                              conjugate->standard_error_px)},
                        {"rms_mismatch", conjugate->rms_mismatch},
                        {"rms_mismatch_other_sense", conjugate->rms_mismatch_other_sense},
                        {"loop_u0_px", loop_u0_px},
                        {"loop_uncertainty_px", loop_u0_sigma_px()},
                        {"loop_uncertainty_covering_px", loop_sigma},
                        {"uncertainty_covering_px", quarters_sigma},
                        {"difference_px", difference},
                        {"consistent", scale <= 2.0},
                        {"scale_factor", scale},
                        {"loop_uncertainty_scaled_px", loop_sigma * scale},
                        {"uncertainty_scaled_px", quarters_sigma * scale}};
  }
  if (repeat)
    r["repeat_exposure"] = {{"views", {0, repeat->last_view}},
                            {"rms_difference", repeat->rms_difference},
                            {"shift_px", repeat->shift_px},
                            {"shift_sigma_px", repeat->shift_sigma_px},
                            {"moved", repeat->moved()}};
  r["seconds"] = seconds;
  return r;
}

std::string RefineScanSummary::brief() const {
  std::ostringstream b;
  b << "held-out projection RMS " << result.heldout_rms_before << " -> " << result.heldout_rms_after << "; sharpness "
    << result.sharpness_before << " -> " << result.sharpness_after << " per mm; accepted:";
  bool any = false;
  for (const auto& e : result.effects)
    if (e.accepted) {
      b << " " << e.name;
      any = true;
    }
  if (!any) b << " nothing";
  return b.str();
}

}  // namespace ctk
