#pragma once
// The spectrum a polychromatic simulation integrates over: a tungsten tube's bremsstrahlung by
// Kramers' law (photons per keV proportional to (kVp - E) / E; characteristic lines neglected),
// hardened by an aluminium filter and weighted by photon energy, as an energy-integrating
// detector sees it. Energies below the tables' 10 keV are dropped (a 1 mm aluminium filter
// already removes 93 % of them).
#include <vector>

namespace ctk {

struct SpectrumBin {
  double energy_kev = 0;  // bin centre
  double weight = 0;      // share of the open-beam signal; the weights sum to 1
};

struct XraySpectrum {
  double kvp = 0;
  double filter_al_mm = 0;
  std::vector<SpectrumBin> bins;

  /// Signal-weighted mean energy (keV).
  double mean_energy_kev() const;
  /// The open-beam signal left after a path of `thickness_mm` of `material` (0..1).
  double transmission(const char* material, double thickness_mm) const;
};

/// Throws std::invalid_argument for kVp outside (15, 150] keV, a negative filter or bin width.
XraySpectrum tube_spectrum(double kvp, double filter_al_mm, double bin_kev = 5.0);

}  // namespace ctk
