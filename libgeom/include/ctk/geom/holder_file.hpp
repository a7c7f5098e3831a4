#pragma once
// A holder described once and declared by any number of scans: a ctk-holder/1 file, or one of
// the holders ctk knows by name. The same description is the `holder` block of a ctk-scan/1 file
// (scan-format.md), which may also name such a file instead of spelling the holder out.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "ctk/core/json_access.hpp"
#include "ctk/geom/helix.hpp"

namespace ctk {

/// The holder block: `helix` {radius_mm, rho_rad_per_mm or pitch_mm, phase_rad},
/// `sphere_diameter_mm`, the centres as `spheres_mm` [[u, v, w], ...] or as `spheres_on_helix`
/// {count, tau_mm: [first, last]} (equally spaced in tau), and optionally `wall`
/// {inner_radius_mm, outer_radius_mm, ends_mm} and `body` {mesh: an STL file (relative: beside the
/// file naming it), unit_mm (1), material ("pom")}. Refusals name the file and the key.
Holder holder_from_json(const JsonNode& node);
/// The block as holder_from_json reads it (centres always listed).
nlohmann::json holder_to_json(const Holder& holder);

/// A ctk-holder/1 file: {"format": "ctk-holder/1", "name": ..., the holder block's keys, and
/// optionally `measurement`: how the centres were measured (written by `ctk holder measure`)}.
Holder read_holder_file(const std::filesystem::path& file);

/// The holders ctk knows by name: "reference" (reference_helix_holder) and "thesis-first".
std::vector<std::string> builtin_holder_names();
/// A built-in holder by name, or a ctk-holder/1 file (a name ending in .json); InputError
/// naming what it is not.
Holder holder_named(const std::string& name_or_file);

/// The thesis' first holder: 50 spheres of 0.678 mm in a 3-D printed tube of 35 mm inner
/// diameter and 56 mm height. The thesis gives those four numbers; the rest is ours: a 2 mm wall,
/// the spheres on its outside (helix radius 19.5 mm), two turns over 48 mm centred on the origin.
Holder thesis_first_holder();

}  // namespace ctk
