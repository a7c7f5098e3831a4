#pragma once
// How good a reconstruction is against the truth: the RMSE over the sample region (which the
// thesis did not have), and the thesis' line-profile gradient magnitude, taken where the truth's
// profile has an edge (sharp, full-contrast edges raise it; between edges a gradient would only
// measure noise and streaks). Three profiles cross only a handful of edges, so that figure moves
// by tens of percent with the noise of one run; the same measure over every axis-parallel line
// of the region (every edge voxel pair of the truth) is the stable one.
// Under a polychromatic beam an absorber reconstructs to a level set by beam hardening (an
// aluminium plate of 0.070 /mm at 60 keV comes out at 0.094 to 0.097 /mm from a 90 kV beam, from
// every trajectory tried), and on a large absorber that offset dominates the RMSE. The RMSE
// outside the absorbers, and off the voxels touching them, measures what a trajectory does to the
// rest of the sample: the streaks and the blur it leaves there.
// Plastics harden the beam too, and their levels dominate the RMSE of samples without metal: on
// random sample 3 a PVC block of 0.046 /mm at 60 keV reconstructs at 0.074 from the whole sphere,
// and the trajectory an oracle found by searching on the RMSE (5.9 % below the whole sphere's)
// brought it to 0.072 by looking along the block's longest paths, where the beam hardens most:
// a better level by hardening, not a better image. So, given the truth split by material, each
// material is also compared at the level the reconstruction gives it (x ~ sum_m a_m t_m, fitted
// by least squares over the region): that RMSE is what is left of blur, streaks, cupping and
// noise, the errors a trajectory controls, and the levels a_m say how far the spectrum moved each
// material (a lab corrects them by calibration, not by choosing views).
#include <array>
#include <string>
#include <vector>

#include "ctk/plan/absorber_segmentation.hpp"

namespace ctk {

struct LineProfile {
  int axis = 0;                  // along x, y or z
  std::array<int, 3> through{};  // voxel the line passes through
  std::vector<float> reconstruction, truth;
};

struct MaterialLevel {
  std::string material;
  double level = 1;  // a_m: the level the reconstruction gives the material over its true one
};

struct TrajectoryQuality {
  double rmse_per_mm = 0;                    // over the sample region
  double rmse_outside_absorbers_per_mm = 0;  // over the region less the absorbers and their face neighbours
  double profile_gradient_per_mm2 = 0;       // mean |d mu / ds| across the truth's edges on the profiles
  double truth_profile_gradient_per_mm2 = 0;
  double edge_gradient_per_mm2 = 0;  // the same over every axis-parallel line of the region
  double truth_edge_gradient_per_mm2 = 0;
  /// With the truth split by material: the RMSE over the region against the truth with each
  /// material at its fitted level, and those levels (materials with no voxel in the region left out).
  double rmse_level_matched_per_mm = 0;
  std::vector<MaterialLevel> material_levels;
  /// The edge gradient over the lines along x, y and z alone: along z it measures the faces
  /// across the holder axis, which a circle about that axis sees least well.
  std::array<double, 3> edge_gradient_along_per_mm2{};
  std::vector<LineProfile> profiles;
};

/// `truth` has the reconstruction's layout. The profiles run along x, y and z through
/// `profile_through` (a voxel), clipped to the sample region. Voxels whose truth is above
/// `absorber_above_per_mm` are absorbers. `materials`, the truth split by material (adding up to
/// `truth`, same layout), adds the level-matched RMSE and the levels; empty, they stay unset.
TrajectoryQuality trajectory_quality(const Volume& reconstruction, const Volume& truth, const SampleRegion& region,
                                     const std::array<int, 3>& profile_through, float absorber_above_per_mm,
                                     const std::vector<MaterialVolume>& materials = {});

/// The voxel at the attenuation-weighted centre of the truth inside the region.
std::array<int, 3> centre_of_mass_voxel(const Volume& truth, const SampleRegion& region);

}  // namespace ctk
