// The markerless loop: a simulated circular scan whose detector sits 0.8 px off the declared
// principal point must get the offset back (and nothing else), a correct one must get nothing;
// and on the measured pepper (../shared/data/real) the loop must find the axis' column that
// conjugate rays and the scanner's own record give (119.2, 119.13), starting from the centre.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "../test_support.hpp"
#include "ctk/geom/scan_import.hpp"
#include "ctk/measure/measurements.hpp"
#include "ctk/phantoms/builtin_phantoms.hpp"
#include "ctk/phantoms/render.hpp"
#include "ctk/recon/markerless_refinement.hpp"

namespace ctk {
namespace {

std::vector<ProjectionMatrix> orbit_matrices(const Detector& d, const Eigen::Vector2d& pp, int views) {
  CircularOrbit orbit;
  orbit.detector = d;
  orbit.principal_point_px = pp;
  orbit.source_to_axis_mm = 400;
  orbit.source_to_detector_mm = 600;
  for (int k = 0; k < views; ++k) orbit.angles_rad.push_back(2 * M_PI * (k + 0.5) / views);
  return circular_matrices(orbit);
}

const RefinedEffect* find(const RefinementResult& r, const std::string& name) {
  for (const auto& e : r.effects)
    if (e.name == name) return &e;
  return nullptr;
}

struct Simulated {
  ProjectionStack b;
  std::vector<ProjectionMatrix> nominal;
};

// Shepp-Logan seen with the detector `true_shift_px` off the declared centre; declared: centred.
// `step_px`: the detector moves by this much more across the beam at mid-scan.
Simulated simulate(double true_shift_px, double step_px = 0) {
  const Detector d{96, 72, 1.2, 1.2};
  const int views = 120;
  const auto before = orbit_matrices(d, d.centre_px() + Eigen::Vector2d(true_shift_px, 0), views);
  const auto after = orbit_matrices(d, d.centre_px() + Eigen::Vector2d(true_shift_px + step_px, 0), views);
  std::vector<ProjectionMatrix> truth(before.begin(), before.begin() + views / 2);
  truth.insert(truth.end(), after.begin() + views / 2, after.end());
  Simulated s{ProjectionStack(views, d.rows, d.cols), orbit_matrices(d, d.centre_px(), views)};
  const Phantom phantom = shepp_logan_phantom(28.0, 0.02);
#pragma omp parallel for schedule(dynamic)
  for (int v = 0; v < views; ++v) {
    const Image im = render_line_integrals(phantom, truth[static_cast<std::size_t>(v)], d, {2, std::nullopt, std::nullopt});
    std::copy(im.pixels.begin(), im.pixels.end(), s.b.view(v));
  }
  return s;
}

RefinementResult refine(const Simulated& s, const std::vector<std::string>& candidates) {
  const Detector d{96, 72, 1.2, 1.2};
  const VolumeLayout coarse = VolumeLayout::centred({96, 96, 88}, Eigen::Vector3d::Constant(0.8));
  const VolumeLayout fine = VolumeLayout::centred({96, 96, 1}, Eigen::Vector3d::Constant(0.8));
  const ConsistencyProbe probe(s.b, s.nominal, d, coarse, interleaved_split(s.b.views));
  RefinementOptions o;
  o.candidates = candidates;
  return refine_markerless(probe, fine, o);
}

TEST(MarkerlessRefinement, RecoversADetectorOffsetAndAcceptsNothingElse) {
  const RefinementResult r = refine(simulate(0.8), {"detector_offset", "detector_roll", "magnification"});
  const RefinedEffect* offset = find(r, "detector_offset");
  ASSERT_NE(offset, nullptr);
  EXPECT_TRUE(offset->accepted);
  EXPECT_NEAR(offset->parameters["u0_px"].get<double>(), 47.5 + 0.8, 0.1);
  EXPECT_NEAR(offset->parameters["v0_px"].get<double>(), 35.5, 1.0);
  EXPECT_LT(offset->heldout_rms_after, 0.8 * offset->heldout_rms_before);
  EXPECT_GT(offset->sharpness_after, offset->sharpness_before);
  for (const auto& e : r.effects)
    if (e.name != "detector_offset") {
      EXPECT_FALSE(e.accepted) << e.name << " z " << e.z << " " << e.parameters.dump();
    }
}

// The detector moving by 2 px at mid-scan: the views' scatter hardly sees it, the halves of the
// scan in time do (each half's fit against the yardstick of the whole scan, which takes up most of
// the step as a displaced object: 0.1 of it is left to part them), and the uncertainty stated from
// them covers their difference; on a still scan they agree.
TEST(MarkerlessRefinement, ADetectorMovedAtMidScanPartsTheHalvesInTime) {
  const auto halves = [](const RefinementResult& r) {
    const RefinedEffect* offset = find(r, "detector_offset");
    EXPECT_NE(offset, nullptr);
    return offset ? offset->halves_in_time.at("u0_px") : nlohmann::json();
  };
  const nlohmann::json moved = halves(refine(simulate(0.8, 2.0), {"detector_offset"}));
  const nlohmann::json still = halves(refine(simulate(0.8), {"detector_offset"}));
  std::cout << "halves in time, moved at mid-scan: " << moved.dump() << "\nstill: " << still.dump() << "\n";
  const double parted = moved.at("second").get<double>() - moved.at("first").get<double>();
  EXPECT_GT(parted, 0.06);
  EXPECT_NEAR(moved.at("uncertainty").get<double>(), std::max(parted / 2, moved.at("within").get<double>()), 1e-12);
  EXPECT_GT(parted / 2, 1.5 * moved.at("within").get<double>());
  EXPECT_LT(std::abs(still.at("second").get<double>() - still.at("first").get<double>()), 0.02);
}

TEST(MarkerlessRefinement, ACorrectGeometryGetsNothing) {
  const RefinementResult r = refine(simulate(0.0), {"detector_offset", "detector_roll"});
  for (const auto& e : r.effects) EXPECT_FALSE(e.accepted) << e.name << " z " << e.z << " " << e.parameters.dump();
  EXPECT_NEAR(r.heldout_rms_after, r.heldout_rms_before, 1e-12);
}

// A detector whose pixels keep a fixed offset in every view (gains 0.5 % apart between the flat
// and the projections, and one defective column 5 % off) reconstructs with rings. pixel_gain must be accepted on held-out views
// and find the column; column_gain, which cannot describe pixel-to-pixel differences down a column, must not win; nothing
// geometric may move. On the same scan without the pattern neither is accepted.
TEST(MarkerlessRefinement, AFixedPixelPatternIsFoundAndADefectiveColumnNamed) {
  Simulated s = simulate(0.0);
  const Detector d{96, 72, 1.2, 1.2};
  const Simulated clean_scan = s;
  std::vector<float> pattern(s.b.pixels_per_view());
  std::uint32_t state = 7;
  for (auto& x : pattern) {
    state = state * 1664525u + 1013904223u;
    x = 0.005f * (static_cast<float>(state >> 8) / 8388608.0f - 1.0f) * 1.732f;  // uniform, RMS 0.005: gains 0.5 % apart
  }
  constexpr int kDefective = 61;
  for (int r = 0; r < d.rows; ++r) pattern[static_cast<std::size_t>(r * d.cols + kDefective)] += 0.05f;
  for (int v = 0; v < s.b.views; ++v)
    for (std::size_t p = 0; p < s.b.pixels_per_view(); ++p) s.b.view(v)[p] += pattern[p];

  const RefinementResult r = refine(s, {"detector_offset", "pixel_gain", "column_gain"});
  const RefinedEffect* gain = find(r, "pixel_gain");
  ASSERT_NE(gain, nullptr);
  ASSERT_TRUE(gain->accepted) << gain->note << " " << gain->parameters.dump() << " z " << gain->z;
  EXPECT_EQ(gain->parameters["largest_at_column"].get<int>(), kDefective);
  // The defective pixel's value: 0.05 plus its own gain (within +-0.0087) and what the object's
  // profile leaves (0.02 at worst on the scan without the pattern).
  EXPECT_NEAR(gain->parameters["largest"].get<double>(), 0.05, 0.0087 + 0.02);
  // Most of what the pattern added to the held-out mean square is gone (the yardstick's own error,
  // the scan without the pattern's RMS, stays).
  const double clean = refine(clean_scan, {"detector_offset"}).heldout_rms_before;
  const auto excess = [&](double rms) { return rms * rms - clean * clean; };
  EXPECT_LT(excess(gain->heldout_rms_after), 0.4 * excess(gain->heldout_rms_before));
  for (const auto& e : r.effects)
    if (e.name == "detector_offset") {
      EXPECT_FALSE(e.accepted) << e.parameters.dump();
    }
  EXPECT_EQ(r.effects.front().name, "pixel_gain");

  const RefinementResult null = refine(clean_scan, {"pixel_gain", "column_gain"});
  for (const auto& e : null.effects) EXPECT_FALSE(e.accepted) << e.name << " z " << e.z << " " << e.parameters.dump();
}

TEST(MarkerlessRefinement, PepperAxisColumnFromTheDetectorCentre) {
  const auto dir = testing::shared_data_dir() / "flexray-pepper-cone";
  CircularOrbit orbit;
  orbit.detector = {239, 190, 0.5984, 0.5984};
  orbit.principal_point_px = orbit.detector.centre_px();  // (119, 94.5): the detector centre, where the loop starts
  orbit.source_to_axis_mm = 1001.305645;
  orbit.source_to_detector_mm = 1098.0;
  for (int k = 0; k < 225; ++k) orbit.angles_rad.push_back((0.7 + 1.6 * k) * M_PI / 180);
  const std::vector<ProjectionMatrix> matrices = circular_matrices(orbit);
  ProjectionSet p;
  p.files_pattern = (dir / "scan_%05d.tif").string();
  p.count = 225;
  p.kind = ProjectionKind::counts;
  p.flat = {(dir / "io000000.tif").string()};
  p.dark = {(dir / "di000000.tif").string()};
  const auto scratch = testing::scratch_dir();
  const ImportedScan imported = import_matrices(orbit.detector, matrices, p, scratch / "scan.json");
  write_imported_scan(imported, scratch / "scan.json");
  const ScanDescription scan = read_scan(scratch / "scan.json");
  ASSERT_TRUE(scan.matrices);
  const Measurements m = load_measurements(scan, scan.matrices->geometry, {false});
  ASSERT_EQ(m.line_integrals.views, 225);

  const VolumeLayout coarse = VolumeLayout::centred({120, 120, 114}, Eigen::Vector3d::Constant(1.0914));
  const VolumeLayout fine = VolumeLayout::centred({240, 240, 1}, Eigen::Vector3d::Constant(0.5457));
  const ConsistencyProbe probe(m.line_integrals, m.matrices, scan.detector, coarse, interleaved_split(225));
  RefinementOptions o;
  o.candidates = {"detector_offset"};
  const RefinementResult r = refine_markerless(probe, fine, o);
  const RefinedEffect* offset = find(r, "detector_offset");
  ASSERT_NE(offset, nullptr);
  ASSERT_TRUE(offset->accepted) << offset->note << " " << offset->parameters.dump() << " z " << offset->z;
  const double u0 = offset->parameters["u0_px"].get<double>(), v0 = offset->parameters["v0_px"].get<double>();
  std::cout << "pepper: u0 " << u0 << " +- " << offset->uncertainty["u0_px"] << ", v0 " << v0 << " +- "
            << offset->uncertainty["v0_px"] << "; held-out RMS " << offset->heldout_rms_before << " -> "
            << offset->heldout_rms_after << "\n";
  EXPECT_NEAR(u0, 119.2, 0.3);
  EXPECT_NEAR(v0, 95.3, 1.5);  // the scanner's record; weakly observable, so a loose bound
  const double v0_sigma = offset->uncertainty["v0_px"].get<double>();
  EXPECT_GT(v0_sigma, offset->uncertainty["u0_px"].get<double>());  // reported, and weaker than u0
  EXPECT_GT(offset->sharpness_after, offset->sharpness_before);
}

}  // namespace
}  // namespace ctk
