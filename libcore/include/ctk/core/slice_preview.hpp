#pragma once
// A volume's slice as a person reads it: drawn as the scanner shows it (z up in the coronal and
// sagittal slices), enlarged to a legible size, its axes named, a scale bar in mm and a grey bar
// saying which values black and white stand for. Written as PNG, atomically (chart.hpp).
#include <filesystem>
#include <string>

#include "ctk/core/volume.hpp"

namespace ctk {

/// Slice `index` across `axis` (0: x, giving y across and z up; 1: y, giving x across and z up;
/// 2: z, giving x across and y down), grey levels linear from `low` (black) to `high` (white),
/// labelled with `unit` (what the values are, e.g. "1/mm").
void write_slice_preview(const Volume& volume, int axis, int index, float low, float high, const std::string& unit,
                         const std::filesystem::path& file);

}  // namespace ctk
