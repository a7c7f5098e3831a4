// The command-line test's other-tool scans and their check:
//   write_vendor_scans write <folder>          NXtomo (<folder>/nxtomo/scan.nx) and Nikon (<folder>/nikon/ball.xtekct)
//   write_vendor_scans check <volume> nxtomo|nikon   the two balls where they were put (exit 1 otherwise)
#include <cstdio>
#include <iostream>

#include "ctk/core/volume_file.hpp"
#include "vendor_scans.hpp"

namespace {

using namespace ctk;

// Centroid of the voxels above half a ball's attenuation within radius + 2 mm of where it was put.
int check(const std::filesystem::path& volume_file, const Eigen::Vector3d& offset) {
  const Volume v = read_volume(volume_file);
  int failures = 0;
  for (const testing::Ball& b : testing::two_balls()) {
    const Eigen::Vector3d expected = b.centre_mm + offset;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double weight = 0;
    for (int k = 0; k < v.layout.size[2]; ++k)
      for (int j = 0; j < v.layout.size[1]; ++j)
        for (int i = 0; i < v.layout.size[0]; ++i) {
          const Eigen::Vector3d x = v.layout.origin_mm + v.layout.voxel_mm.cwiseProduct(Eigen::Vector3d(i, j, k));
          const float value = v.at(i, j, k);
          if ((x - expected).norm() < b.radius_mm + 2 && value > 0.5 * b.attenuation_per_mm) {
            sum += value * x;
            weight += value;
          }
        }
    const Eigen::Vector3d found = weight > 0 ? Eigen::Vector3d(sum / weight) : Eigen::Vector3d::Constant(1e9);
    const double error = (found - expected).norm();
    std::printf("ball of %.0f mm at (%.2f, %.2f, %.2f): found at (%.2f, %.2f, %.2f), %.3f mm off\n", b.radius_mm, expected.x(),
                expected.y(), expected.z(), found.x(), found.y(), found.z(), error);
    if (!(error < 0.3)) ++failures;
  }
  return failures == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc > 1 ? argv[1] : "";
  if (mode == "write" && argc == 3) {
    const std::filesystem::path folder = argv[2];
    std::filesystem::create_directories(folder / "nxtomo");
    testing::write_nxtomo(folder / "nxtomo" / "scan.nx", testing::nxtomo_scan(testing::ConeSetup{}, testing::two_balls()));
    testing::write_nikon(folder / "nikon", testing::NikonContent{}, testing::two_balls());
    return 0;
  }
  if (mode == "check" && argc == 4) {
    // ctk reconstructs in the sample frame; NXtomo's axis passes through it at the origin, and so
    // does Nikon's (the sample frame's origin is on the axis, its offset in the lab only).
    return check(argv[2], Eigen::Vector3d::Zero());
  }
  std::cerr << "usage: write_vendor_scans write <folder> | check <volume> nxtomo|nikon\n";
  return 2;
}
