#include "ctk/phantoms/xray_spectrum.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "ctk/phantoms/material_attenuation.hpp"

namespace ctk {

double XraySpectrum::mean_energy_kev() const {
  double sum = 0;
  for (const SpectrumBin& b : bins) sum += b.weight * b.energy_kev;
  return sum;
}

double XraySpectrum::transmission(const char* material, double thickness_mm) const {
  double sum = 0;
  for (const SpectrumBin& b : bins) sum += b.weight * std::exp(-linear_attenuation_per_mm(material, b.energy_kev) * thickness_mm);
  return sum;
}

XraySpectrum tube_spectrum(double kvp, double filter_al_mm, double bin_kev) {
  if (!(kvp > 15.0 && kvp <= kMaxTabulatedEnergyKeV))
    throw std::invalid_argument("tube voltage " + std::to_string(kvp) + " kV: expected more than 15 and at most 150 kV");
  if (!(filter_al_mm >= 0)) throw std::invalid_argument("the aluminium filter must not be negative");
  if (!(bin_kev > 0)) throw std::invalid_argument("the spectrum's bin width must be positive");
  XraySpectrum s{kvp, filter_al_mm, {}};
  const int count = std::max(1, static_cast<int>(std::ceil((kvp - kMinTabulatedEnergyKeV) / bin_kev)));
  const double width = (kvp - kMinTabulatedEnergyKeV) / count;
  double total = 0;
  for (int i = 0; i < count; ++i) {
    const double e = kMinTabulatedEnergyKeV + (i + 0.5) * width;
    const double photons = (kvp - e) / e;  // Kramers, per keV
    const double filtered = photons * std::exp(-linear_attenuation_per_mm("aluminium", e) * filter_al_mm);
    s.bins.push_back({e, filtered * e});  // energy-integrating detector
    total += filtered * e;
  }
  for (SpectrumBin& b : s.bins) b.weight /= total;
  return s;
}

}  // namespace ctk
