#pragma once
// The phantoms the toolkit ships, built in code so they always match the holder a scan declares.
// `ctk phantom --write` saves any of them as a ctk-phantom/1 file to inspect or edit.
// Attenuation coefficients are for an effective energy near 60 keV (see materials below).
#include <string>
#include <vector>

#include "ctk/geom/helix.hpp"
#include "ctk/phantoms/phantom.hpp"

namespace ctk {

/// Linear attenuation (1/mm) near 60 keV: mass attenuation coefficient (NIST XCOM) times density.
namespace material {
inline constexpr double pom = 0.027;          // polyoxymethylene, 1.41 g/cm3
inline constexpr double aluminium = 0.075;    // 2.70 g/cm3
inline constexpr double pvc = 0.046;          // 1.38 g/cm3 (chlorine raises it)
inline constexpr double abs_plastic = 0.020;  // toy bricks, 1.05 g/cm3
}  // namespace material

/// The helix holder: a POM tube (`holder.wall`, by default inner diameter 50 mm and a 3 mm wall;
/// 118 mm tall, axis +w, centred on the holder origin) carrying one aluminium sphere at each of
/// `holder.spheres_mm`.
Phantom helix_holder_phantom(const Holder& holder);
/// Modified 3-D Shepp-Logan (the higher-contrast variant): the unit-cube table scaled to
/// `half_size_mm`, densities times `attenuation_scale_per_mm`.
Phantom shepp_logan_phantom(double half_size_mm = 24.0, double attenuation_scale_per_mm = 0.02);
/// Thesis sample 0: a toy brick 31 x 21 x 31 mm beside a 4 mm PVC plate cut at a slant.
Phantom brick_and_plate_phantom();
/// Thesis sample 1: a cube 22 x 18 x 30 mm with a 7 mm hole under a 32 mm cylinder with two 6 mm
/// holes, beside a 4 x 30 x 50 mm absorber (attenuation 1.5 vs 7.0, in units of 0.01/mm).
Phantom sample1_phantom();
/// Thesis sample 2: an open box holding a 6 x 3 x 10 mm cube with a hole, two cylinders with 2 mm
/// and 0.8 mm holes, and a 1 x 12 x 12 mm absorber.
Phantom sample2_phantom();
/// A walnut-like object for visual checks: a shell and a folded two-lobed kernel.
Phantom walnut_phantom();

std::vector<std::string> builtin_phantom_names();
/// By name ("helix-holder" uses the reference holder). A name that is none of them is bad input:
/// InputError naming it and listing the names.
Phantom builtin_phantom(const std::string& name);

/// Built-in phantoms by name or ctk-phantom/1 files (names ending in .json) as one sample, named
/// "walnut + sample-2"; `warnings` (optional) collects the files' notes.
Phantom sample_of(const std::vector<std::string>& names_or_files, std::vector<std::string>* warnings = nullptr);

}  // namespace ctk
