#include "ctk/phantoms/material_attenuation.hpp"

#include <array>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace ctk {

namespace {

constexpr std::array<double, 10> kEnergiesKeV = {10, 15, 20, 30, 40, 50, 60, 80, 100, 150};
using Table = std::array<double, 10>;

// mu/rho (cm^2/g), NIST X-ray mass attenuation coefficients (Hubbell & Seltzer, NISTIR 5632).
constexpr Table kHydrogen = {0.3854, 0.3764, 0.3695, 0.3570, 0.3458, 0.3355, 0.3260, 0.3091, 0.2944, 0.2651};
constexpr Table kCarbon = {2.373, 0.8071, 0.4420, 0.2562, 0.2076, 0.1871, 0.1753, 0.1610, 0.1514, 0.1347};
constexpr Table kNitrogen = {3.879, 1.236, 0.6178, 0.3066, 0.2288, 0.1980, 0.1817, 0.1639, 0.1529, 0.1353};
constexpr Table kOxygen = {5.952, 1.836, 0.8651, 0.3779, 0.2585, 0.2132, 0.1907, 0.1678, 0.1551, 0.1361};
constexpr Table kAluminium = {26.21, 7.955, 3.442, 1.128, 0.5684, 0.3681, 0.2778, 0.2018, 0.1704, 0.1378};
constexpr Table kChlorine = {57.25, 17.84, 7.739, 2.425, 1.117, 0.6483, 0.4395, 0.2696, 0.2050, 0.1480};
constexpr Table kIron = {170.6, 57.08, 25.68, 8.176, 3.629, 1.958, 1.205, 0.5952, 0.3717, 0.1964};
constexpr Table kCopper = {215.9, 74.05, 33.79, 10.92, 4.862, 2.613, 1.593, 0.7630, 0.4584, 0.2217};

struct Component {
  const Table* element;
  double weight_fraction;
};

struct MaterialData {
  const char* name;
  double density_g_cm3;
  std::vector<Component> components;
};

const std::vector<MaterialData>& materials() {
  // Weight fractions from the chemical formulas; ABS as C15H17N (its usual empirical formula).
  static const std::vector<MaterialData> list = {
      {"pom", 1.41, {{&kHydrogen, 0.067135}, {&kCarbon, 0.400017}, {&kOxygen, 0.532848}}},
      {"pvc", 1.38, {{&kHydrogen, 0.048380}, {&kCarbon, 0.384360}, {&kChlorine, 0.567260}}},
      {"abs", 1.05, {{&kHydrogen, 0.081100}, {&kCarbon, 0.852600}, {&kNitrogen, 0.066300}}},
      {"water", 1.00, {{&kHydrogen, 0.111894}, {&kOxygen, 0.888106}}},
      {"aluminium", 2.699, {{&kAluminium, 1.0}}},
      {"iron", 7.874, {{&kIron, 1.0}}},
      {"copper", 8.96, {{&kCopper, 1.0}}},
  };
  return list;
}

const MaterialData& find_material(const std::string& name) {
  for (const MaterialData& m : materials())
    if (name == m.name) return m;
  std::string names;
  for (const auto& n : known_materials()) names += (names.empty() ? "" : ", ") + n;
  throw std::invalid_argument("unknown material \"" + name + "\" (known: " + names + ")");
}

// Log-log interpolation: attenuation follows a power law of energy between table points.
double interpolate(const Table& table, double energy_kev) {
  std::size_t i = 1;
  while (i + 1 < kEnergiesKeV.size() && kEnergiesKeV[i] < energy_kev) ++i;
  const double t = std::log(energy_kev / kEnergiesKeV[i - 1]) / std::log(kEnergiesKeV[i] / kEnergiesKeV[i - 1]);
  return std::exp(std::log(table[i - 1]) + t * (std::log(table[i]) - std::log(table[i - 1])));
}

}  // namespace

std::vector<std::string> known_materials() {
  std::vector<std::string> names;
  for (const MaterialData& m : materials()) names.emplace_back(m.name);
  return names;
}

bool is_known_material(const std::string& name) {
  for (const MaterialData& m : materials())
    if (name == m.name) return true;
  return false;
}

double mass_attenuation_cm2_per_g(const std::string& material, double energy_kev) {
  const MaterialData& m = find_material(material);
  if (!(energy_kev >= kMinTabulatedEnergyKeV && energy_kev <= kMaxTabulatedEnergyKeV))
    throw std::invalid_argument("photon energy " + std::to_string(energy_kev) + " keV is outside the tables (10 to 150 keV)");
  double sum = 0;
  for (const Component& c : m.components) sum += c.weight_fraction * interpolate(*c.element, energy_kev);
  return sum;
}

double linear_attenuation_per_mm(const std::string& material, double energy_kev) {
  return 0.1 * find_material(material).density_g_cm3 * mass_attenuation_cm2_per_g(material, energy_kev);
}

double attenuation_ratio(const std::string& material, double energy_kev) {
  return mass_attenuation_cm2_per_g(material, energy_kev) / mass_attenuation_cm2_per_g(material, kReferenceEnergyKeV);
}

}  // namespace ctk
