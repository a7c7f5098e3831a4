#pragma once
// Interchange with ASTRA's "cone_vec" geometry: per view 12 numbers (source, detector centre,
// one column step u, one row step v), in volume units (mm here, or scaled by `mm_per_unit`).
#include <array>
#include <filesystem>
#include <vector>

#include "ctk/geom/detector.hpp"
#include "ctk/geom/projection_matrix.hpp"

namespace ctk {

using ConeVec = std::array<double, 12>;

/// The 12 numbers from their four vectors (source, detector centre, column step, row step), each
/// divided by `mm_per_unit`.
ConeVec make_cone_vec(const Eigen::Vector3d& source, const Eigen::Vector3d& detector_centre, const Eigen::Vector3d& u,
                      const Eigen::Vector3d& v, double mm_per_unit = 1.0);

/// Places the detector plane so that one column step is `detector.pitch_u_mm` long (for a
/// matrix composed from the setup this is the physical detector).
ConeVec to_cone_vec(const ProjectionMatrix& P, const Detector& detector, double mm_per_unit = 1.0);
/// P = inv([u | v | o - s]) [I | -s], with o the centre of pixel (0, 0); oriented so the detector
/// lies at positive depth, then normalised.
ProjectionMatrix from_cone_vec(const ConeVec& vec, const Detector& detector, double mm_per_unit = 1.0);

/// Whitespace-separated text, one view per line (ASTRA / CWI ".geom" files).
std::vector<ConeVec> read_cone_vecs(const std::filesystem::path& file);
void write_cone_vecs(const std::vector<ConeVec>& vecs, const std::filesystem::path& file);

}  // namespace ctk
