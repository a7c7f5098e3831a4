#pragma once
// The pictures of a diagnosis report: the image residual as a vector field over the detector
// (mean per cell, magnified) before and after the accepted effects, the mean residual of each
// sphere before and after, and the robot's prediction error view by view before and after.
#include <filesystem>
#include <string>
#include <vector>

#include "ctk/calib/diagnosis.hpp"

namespace ctk {

/// Writes `<stem>.field-before.png`, `<stem>.field-after.png`, `<stem>.spheres.png` and, for
/// robot scans, `<stem>.fk.png`; returns the file names written.
std::vector<std::string> write_diagnosis_pictures(const Diagnosis& d, const ScanObservations& o,
                                                  const std::filesystem::path& stem);

}  // namespace ctk
