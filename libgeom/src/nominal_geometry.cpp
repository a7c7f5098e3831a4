#include "ctk/geom/nominal_geometry.hpp"

#include "ctk/geom/panda.hpp"

namespace ctk {

std::vector<NominalView> nominal_views(const ScanDescription& scan) {
  std::vector<NominalView> out(static_cast<std::size_t>(scan.projections.count));
  if (scan.matrices) {
    for (std::size_t i = 0; i < out.size(); ++i) {
      const auto& v = scan.matrices->geometry.views[i];
      if (v.status == ViewStatus::ok && v.P)
        out[i].P = v.P;
      else
        out[i].reason = v.reason.empty() ? "no matrix for this view" : v.reason;
    }
    return out;
  }
  const auto& panda = *scan.panda;
  const Intrinsics K = scan.intrinsics();
  for (int view = 0; view < scan.projections.count; ++view) {
    auto& nv = out[static_cast<std::size_t>(view)];
    const JointRow* row = panda.joints.find(view);
    if (!row) {
      nv.reason = "no joints row (the robot did not reach this view)";
      continue;
    }
    if (!row->limit_violation.empty()) {
      nv.reason = "joints out of limits: " + row->limit_violation;
      continue;
    }
    panda::Joints q = row->q;
    for (std::size_t j = 0; j < q.size(); ++j) q[j] += panda.joint_offsets_rad[j];
    nv.T_camera_holder = panda.T_camera_base * panda::forward_kinematics(q) * panda.T_flange_holder;
    nv.P = ProjectionMatrix::compose(K, *nv.T_camera_holder);
  }
  return out;
}

Geometry nominal_geometry(const ScanDescription& scan) {
  Geometry g;
  g.detector = scan.detector;
  // A matrices scan's geometry is what its matrices are (a refined scan's are refined ones).
  g.origin = scan.matrices && !scan.matrices->geometry.origin.empty() ? scan.matrices->geometry.origin : "nominal";
  const auto views = nominal_views(scan);
  for (int i = 0; i < static_cast<int>(views.size()); ++i) {
    GeometryView v;
    v.index = i;
    v.projection = scan.projections.file_name(i);
    v.P = views[static_cast<std::size_t>(i)].P;
    v.status = v.P ? ViewStatus::ok : ViewStatus::skipped;
    v.reason = views[static_cast<std::size_t>(i)].reason;
    g.views.push_back(std::move(v));
  }
  return g;
}

Geometry geometry_or_nominal(const ScanDescription& scan, const std::filesystem::path& scan_file,
                             const std::filesystem::path& geometry_file) {
  if (!geometry_file.empty()) return geometry_for_scan(scan, read_geometry(geometry_file));
  Geometry g = nominal_geometry(scan);
  g.file = scan_file;
  return g;
}

}  // namespace ctk
