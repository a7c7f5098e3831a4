#include "ctk/calib/holder_pictures.hpp"

#include <algorithm>
#include <cmath>

#include "ctk/core/chart.hpp"

namespace ctk {

std::vector<std::string> write_holder_pictures(const HolderMeasurement& m, const std::filesystem::path& stem) {
  const std::size_t n = m.measured.spheres_mm.size();
  std::vector<double> offset(n), reach(n), off_helix(n, 0.0);
  double top = 1e-3;
  for (std::size_t k = 0; k < n; ++k) {
    offset[k] = (m.measured.spheres_mm[k] - m.declared.spheres_mm[k]).norm();
    reach[k] = k < m.sigma_mm.size() ? 1.96 * m.sigma_mm[k].norm() : 0.0;  // the offset's 95 % reach in 3-D
    if (k < m.helix.deviation_mm.size()) off_helix[k] = m.helix.deviation_mm[k].norm();
    top = std::max({top, 1.1 * (offset[k] + reach[k]), 1.1 * off_helix[k]});
  }
  const double count = static_cast<double>(std::max<std::size_t>(n, 1));
  Chart chart(760, 300, {-0.5, count - 0.5, 0, top, "each sphere's measured centre", "sphere", "distance (mm)"});
  chart.ticks(std::max(1.0, nice_step(count, 10)), nice_step(top, 5));
  for (std::size_t k = 0; k < n; ++k) {
    const double x = static_cast<double>(k);
    chart.line(x, std::max(0.0, offset[k] - reach[k]), x, offset[k] + reach[k], colour::grey);
    chart.dot(x, offset[k], colour::blue, 3);
    chart.cross(x, off_helix[k], colour::orange, 3);
  }
  chart.legend({{"from its declared centre", colour::blue, Mark::dot},
                {"95 % uncertainty", colour::grey, Mark::line},
                {"from the fitted helix", colour::orange, Mark::cross}});
  const std::filesystem::path png = stem.string() + ".spheres.png";
  chart.save(png);
  return {png.filename().string()};
}

}  // namespace ctk
