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
#include <array>
#include <vector>

#include "ctk/plan/absorber_segmentation.hpp"

namespace ctk {

struct LineProfile {
  int axis = 0;                  // along x, y or z
  std::array<int, 3> through{};  // voxel the line passes through
  std::vector<float> reconstruction, truth;
};

struct TrajectoryQuality {
  double rmse_per_mm = 0;                    // over the sample region
  double rmse_outside_absorbers_per_mm = 0;  // over the region less the absorbers and their face neighbours
  double profile_gradient_per_mm2 = 0;       // mean |d mu / ds| across the truth's edges on the profiles
  double truth_profile_gradient_per_mm2 = 0;
  double edge_gradient_per_mm2 = 0;  // the same over every axis-parallel line of the region
  double truth_edge_gradient_per_mm2 = 0;
  /// The edge gradient over the lines along x, y and z alone: along z it measures the faces
  /// across the holder axis, which a circle about that axis sees least well.
  std::array<double, 3> edge_gradient_along_per_mm2{};
  std::vector<LineProfile> profiles;
};

/// `truth` has the reconstruction's layout. The profiles run along x, y and z through
/// `profile_through` (a voxel), clipped to the sample region. Voxels whose truth is above
/// `absorber_above_per_mm` are absorbers.
TrajectoryQuality trajectory_quality(const Volume& reconstruction, const Volume& truth, const SampleRegion& region,
                                     const std::array<int, 3>& profile_through, float absorber_above_per_mm);

/// The voxel at the attenuation-weighted centre of the truth inside the region.
std::array<int, 3> centre_of_mass_voxel(const Volume& truth, const SampleRegion& region);

}  // namespace ctk
