#include "ctk/calib/diagnosis_pictures.hpp"

#include <algorithm>
#include <cmath>

#include "ctk/core/chart.hpp"

namespace ctk {

namespace {

void write_field(const ScanModelFit& f, const ScanObservations& o, const std::string& title, double magnify,
                 const std::filesystem::path& png) {
  constexpr int kCells = 12;
  const double cols = o.setup.detector.cols, rows = o.setup.detector.rows;
  std::vector<Eigen::Vector2d> sum(kCells * kCells, Eigen::Vector2d::Zero());
  std::vector<int> count(kCells * kCells, 0);
  for (std::size_t i = 0; i < o.views.size(); ++i)
    for (std::size_t k = 0; k < f.residual_px[i].size(); ++k) {
      const Eigen::Vector2d& m = o.views[i].measured_px[k];
      const int cu = std::clamp(static_cast<int>(m.x() / cols * kCells), 0, kCells - 1);
      const int cv = std::clamp(static_cast<int>(m.y() / rows * kCells), 0, kCells - 1);
      sum[static_cast<std::size_t>(cv * kCells + cu)] += f.residual_px[i][k];
      ++count[static_cast<std::size_t>(cv * kCells + cu)];
    }
  // v grows downwards on the detector: the chart's y axis runs from rows (bottom) to 0 (top).
  Chart chart(560, static_cast<int>(560 * rows / cols), {0, cols, rows, 0, title, "u (px)", "v (px)"});
  chart.ticks(nice_step(cols, 6), nice_step(rows, 6));
  for (int c = 0; c < kCells * kCells; ++c) {
    if (count[static_cast<std::size_t>(c)] < 3) continue;
    const Eigen::Vector2d mean = sum[static_cast<std::size_t>(c)] / count[static_cast<std::size_t>(c)];
    const int cell_u = c % kCells, cell_v = c / kCells;
    const double u = (cell_u + 0.5) * cols / kCells, v = (cell_v + 0.5) * rows / kCells;
    chart.dot(u, v, colour::grey, 2);
    chart.line(u, v, u + magnify * mean.x(), v + magnify * mean.y(), colour::red, 2);
  }
  chart.legend({{"cell centre", colour::grey, Mark::dot}, {"mean residual x" + tick_label(magnify), colour::red, Mark::line}});
  chart.save(png);
}

std::vector<double> sphere_means(const ScanModelFit& f, const ScanObservations& o) {
  const std::size_t n = o.setup.holder.spheres_mm.size();
  std::vector<Eigen::Vector2d> sum(n, Eigen::Vector2d::Zero());
  std::vector<int> count(n, 0);
  for (std::size_t i = 0; i < o.views.size(); ++i)
    for (std::size_t k = 0; k < f.residual_px[i].size(); ++k) {
      const auto s = static_cast<std::size_t>(o.views[i].spheres[k]);
      sum[s] += f.residual_px[i][k];
      ++count[s];
    }
  std::vector<double> out(n, 0.0);
  for (std::size_t s = 0; s < n; ++s) out[s] = count[s] ? (sum[s] / count[s]).norm() : 0.0;
  return out;
}

std::vector<double> fk_errors(const ScanObservations& o, const std::vector<Rigid>& reference, const EffectParameters& model) {
  std::vector<double> out;
  for (std::size_t i = 0; i < o.views.size(); ++i)
    out.push_back(
        o.views[i].joints
            ? (reference[i].translation() - robot_predicted_pose(o.setup, model, *o.views[i].joints).translation()).norm()
            : 0.0);
  return out;
}

}  // namespace

std::vector<std::string> write_diagnosis_pictures(const Diagnosis& d, const ScanObservations& o,
                                                  const std::filesystem::path& stem) {
  std::vector<std::string> written;
  auto named = [&](const std::string& what) {
    std::filesystem::path p(stem.string() + "." + what + ".png");
    written.push_back(p.filename().string());
    return p;
  };
  const double magnify = 200;
  write_field(d.before_fit, o, "mean image residual per detector cell, before (x200)", magnify, named("field-before"));
  write_field(d.after_fit, o, "mean image residual per detector cell, after (x200)", magnify, named("field-after"));

  const std::vector<double> before = sphere_means(d.before_fit, o), after = sphere_means(d.after_fit, o);
  double top = 0.02;
  for (double x : before) top = std::max(top, 1.1 * x);
  const auto n = static_cast<double>(before.size());
  Chart spheres(700, 260, {-0.5, n - 0.5, 0, top, "mean image residual per sphere", "sphere", "px"});
  spheres.ticks(nice_step(n, 10), nice_step(top, 5));
  for (std::size_t s = 0; s < before.size(); ++s) {
    spheres.dot(static_cast<double>(s), before[s], colour::red, 3);
    spheres.dot(static_cast<double>(s), after[s], colour::green, 3);
  }
  spheres.legend({{"before", colour::red, Mark::dot}, {"after", colour::green, Mark::dot}});
  spheres.save(named("spheres"));

  if (o.setup.robot) {
    const std::vector<double> fk_before = fk_errors(o, d.after_fit.poses, EffectParameters{}),
                              fk_after = fk_errors(o, d.after_fit.poses, d.model);
    double high = 0.05;
    int last = 1;
    for (std::size_t i = 0; i < fk_before.size(); ++i) {
      high = std::max(high, 1.1 * std::max(fk_before[i], fk_after[i]));
      last = std::max(last, o.views[i].view);
    }
    Chart fk(700, 260, {-0.5, last + 0.5, 0, high, "robot prediction error per view", "view", "mm"});
    fk.ticks(nice_step(last, 10), nice_step(high, 5));
    for (std::size_t i = 0; i < fk_before.size(); ++i) {
      fk.dot(o.views[i].view, fk_before[i], colour::red, 2);
      fk.dot(o.views[i].view, fk_after[i], colour::green, 2);
    }
    fk.legend({{"before", colour::red, Mark::dot}, {"after", colour::green, Mark::dot}});
    fk.save(named("fk"));
  }
  return written;
}

}  // namespace ctk
