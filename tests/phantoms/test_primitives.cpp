// Analytic primitives and phantoms: rendered line integrals against closed-form chord lengths
// (computed here by other formulas than the renderer's clipping), phantom files, bad input.
#include <gtest/gtest.h>

#include <random>

#include "../test_support.hpp"
#include "ctk/core/error.hpp"
#include "ctk/phantoms/builtin_phantoms.hpp"
#include "ctk/phantoms/render.hpp"

namespace ctk {
namespace {

const Detector kDetector{64, 48, 0.8, 0.8};

// A view from an arbitrary direction with the holder origin near the middle of the beam.
ProjectionMatrix oblique_view() {
  const Eigen::Matrix3d R = rotation_from_vector(Eigen::Vector3d(0.4, -0.7, 0.25));
  const Intrinsics K = Intrinsics::from_setup(1500, kDetector, kDetector.centre_px() + Eigen::Vector2d(1.3, -0.6));
  return ProjectionMatrix::compose(K, make_rigid(R, Eigen::Vector3d(0.7, -0.4, 1000)));
}

float pixel(const Image& im, int col, int row) { return im.pixels[static_cast<std::size_t>(row * im.cols + col)]; }

// Visits every pixel with its ray (source, unit direction through the pixel centre).
template <typename F>
void for_each_ray(const ProjectionMatrix& P, F&& f) {
  const Eigen::Vector3d s = P.source_position();
  for (int row = 0; row < kDetector.rows; ++row)
    for (int col = 0; col < kDetector.cols; ++col) f(col, row, s, P.ray_direction(Eigen::Vector2d(col, row)));
}

TEST(Primitives, SphereChordIsTwiceTheHalfChordFromTheCentreDistance) {
  const Eigen::Vector3d centre(2.0, -1.5, 3.0);
  const double r = 9.0, mu = 0.037;
  const Phantom phantom{"sphere", {Primitive::sphere(centre, r, mu)}};
  const ProjectionMatrix P = oblique_view();
  const Image im = render_line_integrals(phantom, P, kDetector, {1, std::nullopt, std::nullopt});
  int hits = 0;
  for_each_ray(P, [&](int col, int row, const Eigen::Vector3d& s, const Eigen::Vector3d& d) {
    const double distance = (centre - s).cross(d).norm();
    const double expected = distance < r ? mu * 2 * std::sqrt(r * r - distance * distance) : 0.0;
    hits += expected > 0;
    ASSERT_NEAR(pixel(im, col, row), expected, 1e-6 * mu * 2 * r) << col << ", " << row;
  });
  EXPECT_GT(hits, 100);
}

TEST(Primitives, CylinderChordFromAxisDistanceAndAngle) {
  // Infinite-cylinder chord 2 sqrt(r^2 - D^2) / sin(theta) (D: distance between the ray and the
  // axis, theta: their angle), compared where both crossings lie on the mantle.
  const Eigen::Vector3d centre(-1.0, 0.5, 2.0);
  const Eigen::Matrix3d R = rotation_from_vector(Eigen::Vector3d(0.3, 1.1, -0.2));
  const double r = 7.0, height = 30.0, mu = 0.02;
  const Phantom phantom{"cylinder", {Primitive::cylinder(centre, r, height, R, mu)}};
  const ProjectionMatrix P = oblique_view();
  const Image im = render_line_integrals(phantom, P, kDetector, {1, std::nullopt, std::nullopt});
  const Eigen::Vector3d axis = R.col(2);
  int compared = 0;
  for_each_ray(P, [&](int col, int row, const Eigen::Vector3d& s, const Eigen::Vector3d& d) {
    const Eigen::Vector3d n = d.cross(axis);
    const double sin_theta = n.norm();
    const double D = std::abs((centre - s).dot(n)) / sin_theta;
    if (D >= r) {
      ASSERT_NEAR(pixel(im, col, row), 0.0, 1e-7) << col << ", " << row;
      return;
    }
    const double chord = 2 * std::sqrt(r * r - D * D) / sin_theta;
    // Axial coordinate of the ray's closest approach to the axis, then of both crossings.
    const Eigen::Vector3d w0 = s - centre;
    const double b = d.dot(axis), dd = d.dot(w0), ee = axis.dot(w0);
    const double t_ray = (b * ee - dd) / (1 - b * b);
    const double z_mid = (w0 + t_ray * d).dot(axis);
    const double z_half = 0.5 * chord * std::abs(b);
    if (std::abs(z_mid) + z_half > 0.5 * height - 1e-6) return;  // leaves through a cap
    ++compared;
    ASSERT_NEAR(pixel(im, col, row), mu * chord, 1e-6 * mu * chord) << col << ", " << row;
  });
  EXPECT_GT(compared, 100);
}

TEST(Primitives, BoxChordBetweenOppositeFaces) {
  // Rays entering and leaving through the two faces normal to local z: chord = 2 h_z / |d_z|.
  const Eigen::Vector3d centre(0.5, 1.0, -2.0);
  const Eigen::Matrix3d R = rotation_from_vector(Eigen::Vector3d(-0.5, 0.2, 0.9));
  const Eigen::Vector3d size(40, 30, 6);
  const double mu = 0.05;
  const Phantom phantom{"box", {Primitive::box(centre, size, R, mu)}};
  const ProjectionMatrix P = oblique_view();
  const Image im = render_line_integrals(phantom, P, kDetector, {1, std::nullopt, std::nullopt});
  int compared = 0;
  for_each_ray(P, [&](int col, int row, const Eigen::Vector3d& s, const Eigen::Vector3d& d) {
    const Eigen::Vector3d p = R.transpose() * (s - centre), q = R.transpose() * d;
    const double hz = 0.5 * size.z();
    for (double face : {-hz, hz}) {
      const Eigen::Vector3d x = p + ((face - p.z()) / q.z()) * q;
      if (std::abs(x.x()) > 0.5 * size.x() || std::abs(x.y()) > 0.5 * size.y()) return;
    }
    ++compared;
    const double chord = 2 * hz / std::abs(q.z());
    ASSERT_NEAR(pixel(im, col, row), mu * chord, 1e-6 * mu * chord) << col << ", " << row;
  });
  EXPECT_GT(compared, 100);
}

TEST(Primitives, HolesSubtractAndContainmentMatchesTheChord) {
  // A tube (cylinder minus bore): a ray through the axis crosses the wall twice.
  const Phantom tube{"tube",
                     {Primitive::cylinder(Eigen::Vector3d::Zero(), 28, 118, Eigen::Matrix3d::Identity(), 0.027),
                      Primitive::cylinder(Eigen::Vector3d::Zero(), 25, 118, Eigen::Matrix3d::Identity(), -0.027)}};
  const double through_axis = tube.line_integral(Eigen::Vector3d(-1000, 0, 0), Eigen::Vector3d::UnitX());
  EXPECT_NEAR(through_axis, 0.027 * 2 * 3, 1e-12);
  EXPECT_NEAR(tube.attenuation_at(Eigen::Vector3d(26.5, 0, 0)), 0.027, 1e-15);
  EXPECT_NEAR(tube.attenuation_at(Eigen::Vector3d(10, 0, 0)), 0.0, 1e-15);
  // A ray starting inside counts only the part ahead of it.
  const Primitive ball = Primitive::sphere(Eigen::Vector3d::Zero(), 5, 1.0);
  EXPECT_NEAR(ball.chord_mm(Eigen::Vector3d(2, 0, 0), Eigen::Vector3d::UnitX()), 3.0, 1e-12);
}

TEST(Primitives, SupersamplingAveragesTransmittedIntensity) {
  // A uniform slab seen face on: every sub-ray has the same integral, so the pixel keeps it;
  // at an edge the pixel reports -log of the mean transmission, below the mean line integral.
  const Phantom slab{"slab",
                     {Primitive::box(Eigen::Vector3d::Zero(), Eigen::Vector3d(20, 20, 10), Eigen::Matrix3d::Identity(), 0.3)}};
  const Intrinsics K = Intrinsics::from_setup(1500, kDetector, kDetector.centre_px());
  const ProjectionMatrix P = ProjectionMatrix::compose(K, make_rigid(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, 1000)));
  const Image fine = render_line_integrals(slab, P, kDetector, {4, std::nullopt, std::nullopt});
  const Image centre_only = render_line_integrals(slab, P, kDetector, {1, std::nullopt, std::nullopt});
  const int c = kDetector.cols / 2, r = kDetector.rows / 2;
  EXPECT_NEAR(pixel(fine, c, r), pixel(centre_only, c, r), 1e-5);
  // Column whose pixel straddles the slab's edge (u of the edge at x = 10 mm, depth 995 mm).
  const double edge_u = P.project(Eigen::Vector3d(10, 0, -5)).x();
  const int edge_col = static_cast<int>(std::lround(edge_u));
  const float v = pixel(fine, edge_col, r);
  EXPECT_GT(v, 0.0f);
  EXPECT_LT(v, pixel(fine, c, r));
}

TEST(Phantoms, BuiltinsRoundTripThroughTheirFiles) {
  const auto dir = testing::scratch_dir();
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (const std::string& name : builtin_phantom_names()) {
    const Phantom p = builtin_phantom(name);
    write_phantom(p, dir / (name + ".json"));
    const Phantom back = read_phantom(dir / (name + ".json"));
    ASSERT_EQ(back.primitives.size(), p.primitives.size()) << name;
    for (int k = 0; k < 200; ++k) {
      const Eigen::Vector3d origin(300 * u(rng), 300 * u(rng), -500);
      const Eigen::Vector3d direction = (Eigen::Vector3d(20 * u(rng), 20 * u(rng), 40 * u(rng)) - origin).normalized();
      ASSERT_NEAR(back.line_integral(origin, direction), p.line_integral(origin, direction), 1e-9) << name;
    }
  }
}

TEST(Phantoms, HolderMatchesTheDeclaredHolder) {
  const Holder holder = reference_helix_holder();
  const Phantom p = helix_holder_phantom(holder);
  ASSERT_EQ(p.primitives.size(), holder.spheres_mm.size() + 2);
  for (std::size_t k = 0; k < holder.spheres_mm.size(); ++k) {
    const Primitive& s = p.primitives[k + 2];
    EXPECT_EQ(s.shape, Shape::sphere);
    EXPECT_LT((s.pose.translation() - holder.spheres_mm[k]).norm(), 1e-12);
    EXPECT_DOUBLE_EQ(2 * s.half_size_mm.x(), holder.sphere_diameter_mm);
  }
  // The wall: 50 mm inside, 3 mm thick.
  EXPECT_NEAR(p.attenuation_at(Eigen::Vector3d(0, 26.5, 50)), material::pom, 1e-15);
  EXPECT_NEAR(p.attenuation_at(Eigen::Vector3d(0, 24.5, 50)), 0.0, 1e-15);
}

TEST(Phantoms, NoBuiltinSampleHasNegativeAttenuationAnywhere) {
  // Holes must lie inside their material: sample every phantom on a 0.5 mm grid.
  for (const std::string& name : builtin_phantom_names()) {
    const Phantom p = builtin_phantom(name);
    double lowest = 0;
    for (double x = -40; x <= 40; x += 0.5)
      for (double y = -40; y <= 40; y += 0.5)
        for (double z = -60; z <= 60; z += 0.5) lowest = std::min(lowest, p.attenuation_at(Eigen::Vector3d(x, y, z)));
    EXPECT_GT(lowest, -1e-12) << name;
  }
}

TEST(Phantoms, TheTruthSplitByMaterialAddsUpToTheTruth) {
  // Sample 1: ABS parts with holes cut in them, an aluminium plate; 1 mm voxels over its extent.
  const Phantom p = builtin_phantom("sample-1");
  const VolumeLayout layout = VolumeLayout::centred({48, 48, 64}, Eigen::Vector3d::Constant(1.0));
  const Volume whole = voxelised(p, layout);
  const std::vector<MaterialVolume> parts = voxelised_per_material(p, layout);
  ASSERT_EQ(parts.size(), 2u);
  EXPECT_EQ(parts[0].material, "abs");
  EXPECT_EQ(parts[1].material, "aluminium");
  double largest_gap = 0, abs_peak = 0, aluminium_peak = 0;
  for (std::size_t v = 0; v < whole.data.size(); ++v) {
    largest_gap =
        std::max(largest_gap, std::abs(static_cast<double>(parts[0].volume.data[v] + parts[1].volume.data[v] - whole.data[v])));
    abs_peak = std::max(abs_peak, static_cast<double>(parts[0].volume.data[v]));
    aluminium_peak = std::max(aluminium_peak, static_cast<double>(parts[1].volume.data[v]));
  }
  EXPECT_LT(largest_gap, 1e-7);
  EXPECT_NEAR(abs_peak, 0.015, 1e-7);  // each share holds its own material alone
  EXPECT_NEAR(aluminium_peak, 0.070, 1e-7);
}

TEST(Phantoms, BadFilesNameTheKey) {
  const auto dir = testing::scratch_dir();
  testing::write_text(dir / "bad.json",
                      R"({"format": "ctk-phantom/1", "primitives": [{"type": "sphere", "center_mm": [0, 0, 0],
                          "radius_mm": 1, "attenuation_per_mm": 0.1}, {"type": "torus", "center_mm": [0, 0, 0],
                          "attenuation_per_mm": 0.1}]})");
  try {
    read_phantom(dir / "bad.json");
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("primitives[1].type"), std::string::npos) << e.what();
  }
  testing::write_text(dir / "neg.json", R"({"format": "ctk-phantom/1", "primitives": [{"type": "box",
                      "center_mm": [0, 0, 0], "size_mm": [1, -2, 1], "attenuation_per_mm": 0.1}]})");
  EXPECT_THROW(read_phantom(dir / "neg.json"), InputError);
  try {
    builtin_phantom("no-such-phantom");
    FAIL() << "an unknown phantom name accepted";
  } catch (const InputError& e) {  // bad input: the command line exits 2
    EXPECT_EQ(e.file(), "no-such-phantom");
    EXPECT_NE(std::string(e.what()).find("sample-2"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ctk
