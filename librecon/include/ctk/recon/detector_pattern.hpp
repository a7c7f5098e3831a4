#pragma once
// A fixed pattern of the detector in the line integrals: what every view shows at the same pixel
// and no object can (a pixel whose gain differs between the flat and the projections, a
// defective column, which reconstructs as a ring). In a circular scan the mean over views is the
// projection of the rotation-averaged object, smooth along a row (up to kinks); what a parabola
// through each pixel's neighbours along the row does not follow is the detector's. The same mean over held-out
// residuals, against its standard error, shows what a model leaves on the detector.
#include <vector>

#include "ctk/core/projection_stack.hpp"

namespace ctk {

struct DetectorPattern {
  int rows = 0, cols = 0;
  bool by_column = false;              // one value per column, the same down every row
  std::vector<double> mean;            // per pixel (row-major)
  std::vector<double> standard_error;  // of each mean, from the scatter between views
  std::vector<bool> used;              // pixels in the rows the costs use
};

/// The mean over `views` of `sign` times each image, per pixel (or per column: the mean down the
/// rows used), leaving out `row_margin` rows at the top and at the bottom.
DetectorPattern mean_pattern(const ProjectionStack& images, const std::vector<int>& views, int row_margin, bool by_column,
                             double sign = 1.0);

/// The pattern's fine part along each row: each mean less the parabola through its neighbours
/// within `half_width` pixels (least squares, refitted without a neighbour that stands out), which
/// follows the smooth profile of the object however steep. 0 outside the used rows.
std::vector<float> fine_part(const DetectorPattern& pattern, int half_width = 3);

/// Mean of (mean / standard error)^2 over the used pixels: about 1 when the means are noise.
double pattern_statistic(const DetectorPattern& pattern);

}  // namespace ctk
