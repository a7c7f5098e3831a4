#include "ctk/phantoms/render.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "ctk/core/error.hpp"
#include "ctk/core/parallel.hpp"
#include "ctk/phantoms/material_attenuation.hpp"

namespace ctk {

void RenderOptions::validate() const {
  require_option(supersampling >= 1, "RenderOptions.supersampling", "at least 1 (rays per pixel and axis)", supersampling);
  if (distortion)
    require_option(std::isfinite(distortion->k1_per_px2), "RenderOptions.distortion.k1_per_px2", "a finite number",
                   distortion->k1_per_px2);
  if (spectrum)
    require_option(!spectrum->bins.empty(), "RenderOptions.spectrum.bins", "at least one energy bin",
                   static_cast<double>(spectrum->bins.size()));
}

namespace {

struct PixelRect {
  int col0 = 0, col1 = -1, row0 = 0, row1 = -1;  // inclusive
};

// Pixels whose rays can meet the primitive: the projection of its bounding box, widened by a
// pixel and by the largest shift distortion causes; the whole detector when the box reaches
// behind the source.
PixelRect pixels_covering(const Primitive& primitive, const ProjectionMatrix& P, const Detector& detector, double margin_px) {
  double u_min = 1e300, u_max = -1e300, v_min = 1e300, v_max = -1e300;
  for (const Eigen::Vector3d& corner : primitive.bounding_corners()) {
    if (P.depth(corner) <= 1e-6) return {0, detector.cols - 1, 0, detector.rows - 1};
    const Eigen::Vector2d uv = P.project(corner);
    u_min = std::min(u_min, uv.x());
    u_max = std::max(u_max, uv.x());
    v_min = std::min(v_min, uv.y());
    v_max = std::max(v_max, uv.y());
  }
  auto clamp_to = [](double x, int n) { return static_cast<int>(std::clamp(x, -1.0, static_cast<double>(n))); };
  return {std::max(0, clamp_to(std::floor(u_min - margin_px), detector.cols)),
          std::min(detector.cols - 1, clamp_to(std::ceil(u_max + margin_px), detector.cols)),
          std::max(0, clamp_to(std::floor(v_min - margin_px), detector.rows)),
          std::min(detector.rows - 1, clamp_to(std::ceil(v_max + margin_px), detector.rows))};
}

double largest_distortion_shift_px(const RenderOptions& options, const Detector& detector) {
  if (!options.distortion) return 0;
  double shift = 0;
  for (int corner = 0; corner < 4; ++corner) {
    const Eigen::Vector2d uv((corner & 1) ? detector.cols : -1, (corner & 2) ? detector.rows : -1);
    shift = std::max(shift, (options.distortion->measured_from_ideal(uv) - uv).norm());
  }
  return shift;
}

// Primitives grouped by material, with how each group's attenuation scales in each energy bin.
struct MaterialGroups {
  std::vector<int> group_of;               // per primitive
  std::vector<std::vector<double>> ratio;  // [group][bin]
  std::vector<double> bin_weight;          // one bin of weight 1 when monochromatic
};

MaterialGroups material_groups(const Phantom& phantom, const std::optional<XraySpectrum>& spectrum) {
  MaterialGroups g;
  if (!spectrum) {
    g.group_of.assign(phantom.primitives.size(), 0);
    g.ratio = {{1.0}};
    g.bin_weight = {1.0};
    return g;
  }
  std::vector<std::string> names;
  for (const Primitive& p : phantom.primitives) {
    const auto found = std::find(names.begin(), names.end(), p.material);
    g.group_of.push_back(static_cast<int>(found - names.begin()));
    if (found == names.end()) names.push_back(p.material);
  }
  for (const SpectrumBin& b : spectrum->bins) g.bin_weight.push_back(b.weight);
  for (const std::string& name : names) {
    std::vector<double> r;
    for (const SpectrumBin& b : spectrum->bins) r.push_back(name.empty() ? 1.0 : attenuation_ratio(name, b.energy_kev));
    g.ratio.push_back(std::move(r));
  }
  return g;
}

}  // namespace

Image render_line_integrals(const Phantom& phantom, const ProjectionMatrix& P, const Detector& detector,
                            const RenderOptions& options) {
  options.validate();
  const int s = options.supersampling;
  const MaterialGroups groups = material_groups(phantom, options.spectrum);
  const std::size_t group_count = groups.ratio.size();
  const std::size_t samples = static_cast<std::size_t>(s) * static_cast<std::size_t>(s);
  const std::size_t pixels = static_cast<std::size_t>(detector.cols) * static_cast<std::size_t>(detector.rows);
  // Line integral at the reference energy per sub-pixel ray and material group.
  std::vector<double> sub(pixels * samples * group_count, 0.0);
  std::vector<unsigned char> touched(pixels, 0);

  const Eigen::Matrix3d M_inverse = P.matrix().leftCols<3>().inverse();
  const Eigen::Vector3d source = P.source_position();
  const double margin = 1.0 + largest_distortion_shift_px(options, detector);

  for (std::size_t k = 0; k < phantom.primitives.size(); ++k) {
    const Primitive& primitive = phantom.primitives[k];
    const std::size_t group = static_cast<std::size_t>(groups.group_of[k]);
    const PixelRect rect = pixels_covering(primitive, P, detector, margin);
    for (int row = rect.row0; row <= rect.row1; ++row)
      for (int col = rect.col0; col <= rect.col1; ++col) {
        const std::size_t pixel =
            static_cast<std::size_t>(row) * static_cast<std::size_t>(detector.cols) + static_cast<std::size_t>(col);
        double* out = &sub[(pixel * group_count + group) * samples];
        for (int b = 0; b < s; ++b)
          for (int a = 0; a < s; ++a) {
            Eigen::Vector2d uv(col + (a + 0.5) / s - 0.5, row + (b + 0.5) / s - 0.5);
            if (options.distortion) uv = options.distortion->ideal_from_measured(uv);
            // M d = (u, v, 1): depth grows along d, so d points away from the source.
            const Eigen::Vector3d direction = (M_inverse * uv.homogeneous()).normalized();
            out[b * s + a] += primitive.line_integral(source, direction);
          }
        touched[pixel] = 1;
      }
  }

  Image image{detector.cols, detector.rows, std::vector<float>(pixels, 0.0f)};
  for (std::size_t pixel = 0; pixel < pixels; ++pixel) {
    if (!touched[pixel]) continue;
    const double* p = &sub[pixel * group_count * samples];
    if (samples == 1 && !options.spectrum) {
      image.pixels[pixel] = static_cast<float>(p[0]);
      continue;
    }
    double transmitted = 0;
    for (std::size_t k = 0; k < samples; ++k)
      for (std::size_t bin = 0; bin < groups.bin_weight.size(); ++bin) {
        double exponent = 0;
        for (std::size_t g = 0; g < group_count; ++g) exponent += groups.ratio[g][bin] * p[g * samples + k];
        transmitted += groups.bin_weight[bin] * std::exp(-exponent);
      }
    image.pixels[pixel] = static_cast<float>(-std::log(transmitted / static_cast<double>(samples)));
  }
  return image;
}

Volume voxelised(const Phantom& phantom, const VolumeLayout& layout) {
  Volume v(layout);
  const auto& n = layout.size;
  parallel_for_dynamic(n[2], [&](int k) {
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        double sum = 0;
        for (int s = 0; s < 8; ++s) {
          const Eigen::Vector3d offset((s & 1) ? 0.25 : -0.25, (s & 2) ? 0.25 : -0.25, (s & 4) ? 0.25 : -0.25);
          sum += phantom.attenuation_at(layout.centre_of(i, j, k) + offset.cwiseProduct(layout.voxel_mm));
        }
        v.at(i, j, k) = static_cast<float>(sum / 8);
      }
  });
  return v;
}

std::vector<MaterialVolume> voxelised_per_material(const Phantom& phantom, const VolumeLayout& layout) {
  std::vector<Phantom> parts;
  std::vector<std::string> materials;
  for (const Primitive& p : phantom.primitives) {
    const auto at = std::find(materials.begin(), materials.end(), p.material);
    if (at == materials.end()) {
      materials.push_back(p.material);
      parts.push_back({phantom.name + " (" + p.material + ")", {p}});
    } else {
      parts[static_cast<std::size_t>(at - materials.begin())].primitives.push_back(p);
    }
  }
  std::vector<MaterialVolume> out;
  for (std::size_t m = 0; m < parts.size(); ++m) out.push_back({materials[m], voxelised(parts[m], layout)});
  return out;
}

}  // namespace ctk
