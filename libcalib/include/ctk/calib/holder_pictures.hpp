#pragma once
// The picture of a holder measurement: each sphere's measured centre against its declared one
// (the offset's length, with the length of its 95 % uncertainty), and each centre's distance from
// the helix fitted through the measured centres.
#include <filesystem>
#include <string>
#include <vector>

#include "ctk/calib/holder_measurement.hpp"

namespace ctk {

/// Writes `<stem>.spheres.png`; returns the file names written.
std::vector<std::string> write_holder_pictures(const HolderMeasurement& m, const std::filesystem::path& stem);

}  // namespace ctk
