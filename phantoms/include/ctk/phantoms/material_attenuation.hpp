#pragma once
// How the materials of the phantoms attenuate X-rays as a function of photon energy: mass
// attenuation coefficients (NIST, Hubbell & Seltzer, total with coherent scattering) of the
// elements they are made of, tabulated from 10 to 150 keV and interpolated log-log, mixed by
// weight fraction. A primitive's `attenuation_per_mm` is its value at the reference energy; its
// material says how that value changes with energy (the ratio of mass attenuations).
#include <string>
#include <vector>

namespace ctk {

/// The energy the phantoms' attenuation coefficients are quoted at (keV).
inline constexpr double kReferenceEnergyKeV = 60.0;
/// The tabulated range (keV): a spectrum must lie inside it.
inline constexpr double kMinTabulatedEnergyKeV = 10.0;
inline constexpr double kMaxTabulatedEnergyKeV = 150.0;

/// Names the tables know: "pom", "pvc", "abs", "water", "aluminium", "iron", "copper".
std::vector<std::string> known_materials();
bool is_known_material(const std::string& name);

/// mu/rho in cm^2/g; throws std::invalid_argument for an unknown material or an energy outside
/// the tabulated range.
double mass_attenuation_cm2_per_g(const std::string& material, double energy_kev);
/// mu in 1/mm at the material's nominal density.
double linear_attenuation_per_mm(const std::string& material, double energy_kev);
/// mu(E) / mu(reference energy): how a primitive's attenuation scales with energy.
double attenuation_ratio(const std::string& material, double energy_kev);

}  // namespace ctk
