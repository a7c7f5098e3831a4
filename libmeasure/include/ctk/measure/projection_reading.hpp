#pragma once
// One projection of a scan as line integrals: "counts" images are normalised with the scan's
// flat and dark, -log((I - dark) / (flat - dark)), with implausible pixels clamped and counted;
// "line_integrals" images come through as they are.
#include <cstddef>
#include <optional>

#include "ctk/core/image_io.hpp"
#include "ctk/geom/scan.hpp"

namespace ctk {

struct FlatDark {
  Image flat, dark;
};

/// The scan's flat and dark frames (counts scans), checked against the detector size.
std::optional<FlatDark> read_flat_dark(const ScanDescription& scan);

/// Line integrals from raw counts; `clamped` counts pixels whose normalised transmission was not
/// in (0, 1.5] and was clamped there (a NaN count stays NaN, for mask_non_finite). Weights (optional) are the detected counts
/// relative to the open beam, (I - dark) / (flat - dark): Poisson statistics give var(p) ~ 1 / counts, and this scaling keeps
/// open-beam weights at 1.
void counts_to_line_integrals(const Image& counts, const Image& flat, const Image& dark, float* line_integrals, float* weights,
                              std::size_t& clamped);

/// Pixels whose line integral is not a finite number (NaN or infinite in a float image, a NaN
/// count) carry no measurement: each becomes the mean of its finite neighbours (0 when none is) so
/// that solvers without weights stay finite, and gets weight 0 where `weights` is given. Returns
/// how many there were.
std::size_t mask_non_finite(Image& line_integrals, float* weights);

/// Projection `view` as line integrals; throws InputError naming the file when it is missing,
/// damaged or of the wrong size. `flat_dark` is required for counts scans. Non-finite pixels are
/// masked (mask_non_finite) and counted in `non_finite`.
Image read_line_integrals(const ScanDescription& scan, int view, const std::optional<FlatDark>& flat_dark,
                          float* weights = nullptr, std::size_t* clamped = nullptr, std::size_t* non_finite = nullptr);

}  // namespace ctk
