// Polychromatic simulation: the material tables agree with the attenuation the phantoms quote at
// the reference energy, the tube spectrum behaves like one, and a rendered polychromatic ray is
// the spectrum-weighted transmission computed independently — so thick parts harden the beam.
#include <gtest/gtest.h>

#include <cmath>

#include "../test_support.hpp"
#include "ctk/core/error.hpp"
#include "ctk/phantoms/builtin_phantoms.hpp"
#include "ctk/phantoms/material_attenuation.hpp"
#include "ctk/phantoms/render.hpp"
#include "ctk/phantoms/xray_spectrum.hpp"

namespace ctk {
namespace {

TEST(MaterialAttenuation, TablesMatchTheReferenceEnergyConstantsOfThePhantoms) {
  EXPECT_NEAR(linear_attenuation_per_mm("pom", kReferenceEnergyKeV), material::pom, 0.03 * material::pom);
  EXPECT_NEAR(linear_attenuation_per_mm("aluminium", kReferenceEnergyKeV), material::aluminium, 0.02 * material::aluminium);
  EXPECT_NEAR(linear_attenuation_per_mm("pvc", kReferenceEnergyKeV), material::pvc, 0.05 * material::pvc);
  EXPECT_NEAR(linear_attenuation_per_mm("abs", kReferenceEnergyKeV), material::abs_plastic, 0.03 * material::abs_plastic);
  // Water at 60 keV: 0.2059 cm^2/g (NIST), a check of the mixing rule on a compound not used above.
  EXPECT_NEAR(mass_attenuation_cm2_per_g("water", 60), 0.2059, 0.002);
  // Log-log interpolation between table points stays between them and is exact on them.
  EXPECT_DOUBLE_EQ(mass_attenuation_cm2_per_g("aluminium", 30), 1.128);
  const double mid = mass_attenuation_cm2_per_g("aluminium", 35);
  EXPECT_LT(mid, 1.128);
  EXPECT_GT(mid, 0.5684);
  EXPECT_DOUBLE_EQ(attenuation_ratio("iron", kReferenceEnergyKeV), 1.0);
  EXPECT_THROW(mass_attenuation_cm2_per_g("unobtainium", 60), std::invalid_argument);
  EXPECT_THROW(mass_attenuation_cm2_per_g("water", 5), std::invalid_argument);
}

TEST(XraySpectrum, WeightsSumToOneAndAFilterHardensTheBeam) {
  const XraySpectrum soft = tube_spectrum(90, 0.5), hard = tube_spectrum(90, 4.0);
  double sum = 0;
  for (const SpectrumBin& b : soft.bins) {
    sum += b.weight;
    EXPECT_GT(b.weight, 0);
    EXPECT_LT(b.energy_kev, 90);
  }
  EXPECT_NEAR(sum, 1.0, 1e-12);
  EXPECT_GT(hard.mean_energy_kev(), soft.mean_energy_kev() + 3);
  EXPECT_GT(soft.mean_energy_kev(), 35);
  EXPECT_LT(hard.mean_energy_kev(), 60);
  // Beam hardening: the effective attenuation of aluminium falls as the path grows.
  const double thin = -std::log(hard.transmission("aluminium", 1)) / 1,
               thick = -std::log(hard.transmission("aluminium", 40)) / 40;
  EXPECT_LT(thick, 0.8 * thin);
  EXPECT_THROW(tube_spectrum(200, 1), std::invalid_argument);
}

Primitive slab(double thickness_mm, const std::string& material) {
  Primitive p = Primitive::box(Eigen::Vector3d::Zero(), Eigen::Vector3d(20, 20, thickness_mm), Eigen::Matrix3d::Identity(),
                               linear_attenuation_per_mm(material, kReferenceEnergyKeV), "slab");
  p.material = material;
  return p;
}

// The central pixel's ray crosses the slab along z, perpendicular to its faces.
double central_pixel(const Phantom& phantom, const RenderOptions& options) {
  const Detector detector{9, 9, 0.5, 0.5};
  const ProjectionMatrix P = ProjectionMatrix::compose(Intrinsics::from_setup(1500, detector, detector.centre_px()),
                                                       make_rigid(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, 1000)));
  const Image image = render_line_integrals(phantom, P, detector, options);
  return image.pixels[4 * 9 + 4];
}

TEST(XraySpectrum, RenderedPolychromaticRayIsTheWeightedTransmission) {
  const XraySpectrum spectrum = tube_spectrum(90, 2.0);
  RenderOptions poly{1, std::nullopt, spectrum};
  double previous_per_mm = 1e9;
  for (double t : {1.0, 5.0, 20.0, 50.0}) {
    const Phantom p{"slab", {slab(t, "aluminium")}};
    const double rendered = central_pixel(p, poly);
    EXPECT_NEAR(rendered, -std::log(spectrum.transmission("aluminium", t)), 1e-4 * std::max(1.0, rendered)) << t;
    EXPECT_LT(rendered / t, previous_per_mm) << "the effective attenuation must fall with thickness";
    previous_per_mm = rendered / t;
  }
  // One bin at the reference energy is the monochromatic renderer.
  const Phantom mixed{"mixed", {slab(10, "aluminium"), slab(30, "pom")}};
  RenderOptions one_bin{1, std::nullopt, XraySpectrum{60, 0, {{kReferenceEnergyKeV, 1.0}}}};
  EXPECT_NEAR(central_pixel(mixed, one_bin), central_pixel(mixed, RenderOptions{1, std::nullopt, std::nullopt}), 1e-6);
  // A primitive with no material attenuates alike at every energy.
  Primitive grey = slab(10, "aluminium");
  grey.material.clear();
  EXPECT_NEAR(central_pixel(Phantom{"grey", {grey}}, poly), 10 * grey.attenuation_per_mm, 1e-5);
}

TEST(XraySpectrum, PhantomFilesCarryMaterialsAndRejectUnknownOnes) {
  const auto dir = testing::scratch_dir();
  const Phantom sample = builtin_phantom("sample-1");
  EXPECT_EQ(sample.primitives.back().material, "aluminium");
  write_phantom(sample, dir / "s.json");
  const Phantom back = read_phantom(dir / "s.json");
  for (std::size_t i = 0; i < sample.primitives.size(); ++i)
    EXPECT_EQ(back.primitives[i].material, sample.primitives[i].material);
  testing::write_text(dir / "bad.json", R"({"format": "ctk-phantom/1", "primitives": [{"type": "sphere", "center_mm": [0, 0, 0],
                          "radius_mm": 1, "attenuation_per_mm": 0.1, "material": "kryptonite"}]})");
  try {
    read_phantom(dir / "bad.json");
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("primitives[0].material"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ctk
