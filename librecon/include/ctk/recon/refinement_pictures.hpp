#pragma once
// The pictures of a markerless refinement: the central slice reconstructed with the geometry
// before and after (one grey scale), their difference, and what the final model still leaves
// fixed on the detector.
#include <filesystem>
#include <string>
#include <vector>

#include "ctk/recon/markerless_refinement.hpp"

namespace ctk {

/// Writes `<stem>.before.png`, `<stem>.after.png`, `<stem>.difference.png` and `<stem>.pattern.png`;
/// returns their file names in that order.
std::vector<std::string> write_refinement_pictures(const RefinementResult& r, const std::filesystem::path& stem);

}  // namespace ctk
