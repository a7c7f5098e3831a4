#include "ctk/calib/scan_calibration.hpp"

#include <chrono>

#include "ctk/geom/error.hpp"
#include "ctk/geom/nominal_geometry.hpp"
#include "ctk/proj/parallel.hpp"
#include "ctk/proj/projection_reading.hpp"

namespace ctk {

ScanCalibration calibrate_scan(const ScanDescription& scan, const CalibrationOptions& options,
                               const std::function<void(int, int)>& progress) {
  const auto start = std::chrono::steady_clock::now();
  if (!scan.holder) throw InputError("scan", "holder", "calibration needs the holder's spheres (missing)");
  if (static_cast<int>(scan.holder->spheres_mm.size()) < options.min_spheres)
    throw InputError("scan", "holder.spheres_mm",
                     "has " + std::to_string(scan.holder->spheres_mm.size()) + " spheres; a pose needs at least " +
                         std::to_string(options.min_spheres));
  const std::optional<FlatDark> flat_dark = read_flat_dark(scan);
  const std::vector<NominalView> nominal = nominal_views(scan);
  const Eigen::Matrix3d K = scan.intrinsics().K();
  const int n = scan.projections.count;

  ScanCalibration result;
  result.views.resize(static_cast<std::size_t>(n));
  int done = 0;
  parallel_for_dynamic(n, [&](int v) {
    ViewCalibration& out = result.views[static_cast<std::size_t>(v)];
    const NominalView& first_guess = nominal[static_cast<std::size_t>(v)];
    std::optional<Rigid> initial = first_guess.T_camera_holder;
    if (!initial && first_guess.P) initial = first_guess.P->decompose().T_camera_frame;
    if (!initial) {
      out.status = ViewStatus::skipped;
      out.reason = "no pose: " + first_guess.reason;
    } else {
      try {
        const Image image = read_line_integrals(scan, v, flat_dark);
        out = calibrate_view(image, K, *initial, *scan.holder, scan.detector, options);
      } catch (const InputError& e) {
        out.status = ViewStatus::rejected;
        out.reason = std::string("unreadable image: ") + e.what();
      }
    }
#pragma omp critical(ctk_calibration_progress)
    if (progress) progress(++done, n);
  });

  result.geometry.detector = scan.detector;
  for (int v = 0; v < n; ++v) {
    const ViewCalibration& c = result.views[static_cast<std::size_t>(v)];
    GeometryView g;
    g.index = v;
    g.projection = scan.projections.file_name(v);
    g.status = c.status;
    g.reason = c.reason;
    if (c.status == ViewStatus::ok) {
      g.P = c.P;
      g.rms_px = c.rms_px;
      g.spheres_used = c.spheres_used;
    }
    result.geometry.views.push_back(g);
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace ctk
