#pragma once
// What the detector adds to ideal line integrals: blur (focal-spot or motion, per view), spurious
// blobs (dirt, defects), and photon counting. Counts follow I = dark + Poisson(flat * exp(-p)).
#include <cstdint>
#include <random>
#include <vector>

#include "ctk/core/image_io.hpp"

namespace ctk {

/// Gaussian blur of the line integrals (OpenCV), sigma in pixels.
void blur_image(Image& line_integrals, double sigma_px);

/// A disc-shaped spurious blob with the profile of a projected sphere: peak * sqrt(1 - (r/R)^2).
struct Blob {
  double u_px = 0, v_px = 0;
  double radius_px = 0;
  double peak = 0;  // line integral at the centre
};
void add_blob(Image& line_integrals, const Blob& blob);

struct CountsModel {
  double flat_counts = 1e4;  // mean counts above dark with nothing in the beam
  double dark_counts = 100;  // offset of the detector electronics (flat and dark are averaged
                             // frames, so their own noise is neglected)
};

/// What a real detector and source add to the noise-free signal (counts above dark, flat *
/// exp(-p)): the detector's PSF and the focal spot's penumbra blur it (Gaussian sigmas in px,
/// combined in quadrature), scatter adds a smooth background: `scatter_fraction` times the signal
/// blurred over an eighth of the detector (the flat times the transmission seen from afar).
void apply_detector_response(Image& signal, double blur_sigma_px, double scatter_fraction);

/// Mean counts dark + flat * exp(-p) per pixel: the noise-free expectation.
Image expected_counts(const Image& line_integrals, const CountsModel& model);
/// Draws Poisson counts around `expected` - dark (exact below 1000 counts, normal above: the two
/// agree in mean and variance and differ in skewness by < 3 %), plus dark; clamped to the
/// 16-bit range; the number of saturated pixels is returned.
std::size_t draw_counts(Image& expected, const CountsModel& model, std::mt19937_64& rng);

}  // namespace ctk
