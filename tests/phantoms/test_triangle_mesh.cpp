// A CAD part from its STL mesh: a box written as binary and as ASCII STL, read back, gives the
// box primitive's exact chords and inside test along random rays, from outside and from inside;
// placed by a phantom file it projects as the box does; an open or badly wound mesh is refused
// naming its file. A holder file's `body` mesh is drawn in place of the tube, found beside the
// holder file, its material's attenuation at the reference energy.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <random>

#include "../test_support.hpp"
#include "ctk/core/error.hpp"
#include "ctk/geom/holder_file.hpp"
#include "ctk/phantoms/builtin_phantoms.hpp"
#include "ctk/phantoms/material_attenuation.hpp"
#include "ctk/phantoms/phantom.hpp"
#include "ctk/phantoms/render.hpp"
#include "ctk/phantoms/triangle_mesh.hpp"

namespace ctk {
namespace {

// The 12 outward-wound triangles of the box [0, a] x [0, b] x [0, c] (in mm units of the file).
std::vector<std::array<Eigen::Vector3d, 3>> box_triangles(double a, double b, double c) {
  const auto p = [&](int i) { return Eigen::Vector3d(i & 1 ? a : 0, i & 2 ? b : 0, i & 4 ? c : 0); };
  const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  std::vector<std::array<Eigen::Vector3d, 3>> out;
  for (const auto& f : faces) {
    out.push_back({p(f[0]), p(f[1]), p(f[2])});
    out.push_back({p(f[0]), p(f[2]), p(f[3])});
  }
  return out;
}

void write_binary(const std::filesystem::path& file, const std::vector<std::array<Eigen::Vector3d, 3>>& t) {
  std::ofstream out(file, std::ios::binary);
  const std::string header(80, ' ');
  out.write(header.data(), 80);
  const auto n = static_cast<std::uint32_t>(t.size());
  out.write(reinterpret_cast<const char*>(&n), 4);
  for (const auto& tri : t) {
    float values[12] = {0, 0, 0};
    for (int k = 0; k < 3; ++k)
      for (int i = 0; i < 3; ++i) values[3 + 3 * k + i] = static_cast<float>(tri[static_cast<std::size_t>(k)][i]);
    out.write(reinterpret_cast<const char*>(values), sizeof values);
    const std::uint16_t attribute = 0;
    out.write(reinterpret_cast<const char*>(&attribute), 2);
  }
}

void write_ascii(const std::filesystem::path& file, const std::vector<std::array<Eigen::Vector3d, 3>>& t) {
  std::ofstream out(file);
  out << "solid part\n";
  for (const auto& tri : t) {
    out << " facet normal 0 0 0\n  outer loop\n";
    for (const auto& v : tri) out << "   vertex " << v.x() << " " << v.y() << " " << v.z() << "\n";
    out << "  endloop\n endfacet\n";
  }
  out << "endsolid part\n";
}

TEST(TriangleMesh, AnSTLBoxIsTheBoxPrimitive) {
  const auto dir = testing::scratch_dir();
  // A 12 x 8 x 5 mm block written in cm (scale 10), as some CAD exports are.
  const auto triangles = box_triangles(1.2, 0.8, 0.5);
  write_binary(dir / "block.stl", triangles);
  write_ascii(dir / "block-ascii.stl", triangles);
  const TriangleMesh binary = TriangleMesh::read_stl(dir / "block.stl", 10.0);
  const TriangleMesh ascii = TriangleMesh::read_stl(dir / "block-ascii.stl", 10.0);
  EXPECT_EQ(binary.triangle_count(), 12u);
  EXPECT_NEAR(binary.volume_mm3(), 12 * 8 * 5, 1e-3);
  const Eigen::Matrix3d R = rotation_from_vector(Eigen::Vector3d(0.3, -0.2, 0.5));
  const Eigen::Vector3d origin(4, -3, 2);
  const Primitive mesh = Primitive::from_mesh(std::make_shared<const TriangleMesh>(binary), origin, R, 0.05);
  const Primitive box = Primitive::box(origin + R * Eigen::Vector3d(6, 4, 2.5), {12, 8, 5}, R, 0.05);
  std::mt19937 rng(2);
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> inside(-0.45, 0.45);
  int hits = 0;
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector3d d = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
    // From outside towards the block, and from a point inside it.
    const Eigen::Vector3d from =
        i % 2 ? Eigen::Vector3d(box.pose * Eigen::Vector3d(12 * inside(rng), 8 * inside(rng), 5 * inside(rng)))
              : Eigen::Vector3d(origin + R * Eigen::Vector3d(6, 4, 2.5) - 40 * d + Eigen::Vector3d(n(rng), n(rng), n(rng)));
    const double expected = box.chord_mm(from, d);
    ASSERT_NEAR(mesh.chord_mm(from, d), expected, 1e-5) << i;
    hits += expected > 0;
    const TriangleMesh& other = ascii;
    ASSERT_NEAR(other.chord_mm(R.transpose() * (from - origin), R.transpose() * d), expected, 1e-5) << i;
    const Eigen::Vector3d point = box.pose * Eigen::Vector3d(14 * inside(rng), 10 * inside(rng), 7 * inside(rng));
    ASSERT_EQ(mesh.contains(point), box.contains(point)) << i;
  }
  EXPECT_GT(hits, 1500);
}

TEST(TriangleMesh, APhantomFilePlacesTheMeshAndProjectsItAsTheBox) {
  const auto dir = testing::scratch_dir();
  write_ascii(dir / "block.stl", box_triangles(12, 8, 5));
  testing::write_text(dir / "part.json", R"({"format": "ctk-phantom/1", "primitives": [
    {"type": "mesh", "file": "block.stl", "center_mm": [-6, -4, -2.5], "attenuation_per_mm": 0.05, "material": "abs"}]})");
  const Phantom part = read_phantom(dir / "part.json");
  ASSERT_EQ(part.primitives.size(), 1u);
  EXPECT_EQ(phantom_to_json(part)["primitives"][0]["file"], "block.stl");
  Phantom block{"block", {Primitive::box({0, 0, 0}, {12, 8, 5}, Eigen::Matrix3d::Identity(), 0.05)}};
  const Detector detector{48, 40, 0.6, 0.6};
  const Eigen::Matrix3d K = Intrinsics::from_setup(600, detector, detector.centre_px()).K();
  const Rigid T = make_rigid(rotation_from_vector(Eigen::Vector3d(1.1, 0.4, -0.2)), Eigen::Vector3d(0, 0, 350));
  const ProjectionMatrix P = ProjectionMatrix::compose(K, T);
  const Image a = render_line_integrals(part, P, detector), b = render_line_integrals(block, P, detector);
  double largest = 0, difference = 0;
  for (std::size_t i = 0; i < a.pixels.size(); ++i) {
    largest = std::max(largest, static_cast<double>(b.pixels[i]));
    difference = std::max(difference, std::abs(static_cast<double>(a.pixels[i] - b.pixels[i])));
  }
  EXPECT_GT(largest, 0.3);
  EXPECT_LT(difference, 1e-5);
  EXPECT_NEAR(part.attenuation_at({1, 1, 1}), 0.05, 1e-12);
  EXPECT_EQ(part.attenuation_at({7, 1, 1}), 0.0);
}

TEST(TriangleMesh, AHolderFilesBodyIsDrawnInPlaceOfTheTube) {
  const auto dir = testing::scratch_dir();
  std::filesystem::create_directories(dir / "cad");
  // A 10 x 10 x 120 mm bar of PVC along the holder axis, drawn in cm, centred on the origin.
  auto triangles = box_triangles(1, 1, 12);
  for (auto& t : triangles)
    for (auto& v : t) v -= Eigen::Vector3d(0.5, 0.5, 6);
  write_binary(dir / "cad" / "bar.stl", triangles);
  testing::write_text(dir / "holder.json", R"({"format": "ctk-holder/1", "helix": {"radius_mm": 28, "pitch_mm": 40,
    "phase_rad": 0}, "sphere_diameter_mm": 2, "spheres_on_helix": {"count": 5, "tau_mm": [-20, 20]},
    "body": {"mesh": "cad/bar.stl", "unit_mm": 10, "material": "pvc"}})");
  const Holder holder = holder_named((dir / "holder.json").string());
  ASSERT_TRUE(holder.body);
  EXPECT_EQ(holder.body->mesh, dir / "cad" / "bar.stl");  // beside the file that names it
  const Phantom p = helix_holder_phantom(holder);
  ASSERT_EQ(p.primitives.size(), 6u);  // the body and five spheres, no tube
  const double mu = linear_attenuation_per_mm("pvc", kReferenceEnergyKeV);
  EXPECT_NEAR(p.attenuation_at({0, 0, 0}), mu, 1e-12);
  EXPECT_NEAR(p.attenuation_at({4.9, 0, 59}), mu, 1e-12);
  EXPECT_EQ(p.attenuation_at({5.1, 0, 0}), 0.0);   // outside the bar
  EXPECT_EQ(p.attenuation_at({26.5, 0, 0}), 0.0);  // where the tube would be
  EXPECT_NEAR(p.primitives[0].chord_mm({-50, 0, 0}, {1, 0, 0}), 10.0, 1e-5);
  EXPECT_EQ(p.primitives[0].material, "pvc");
  EXPECT_EQ(holder_to_json(holder)["body"]["mesh"], (dir / "cad" / "bar.stl").string());
  testing::write_text(dir / "unknown.json", R"({"format": "ctk-holder/1", "helix": {"radius_mm": 28, "pitch_mm": 40,
    "phase_rad": 0}, "sphere_diameter_mm": 2, "spheres_on_helix": {"count": 5, "tau_mm": [-20, 20]},
    "body": {"mesh": "cad/bar.stl", "material": "unobtainium"}})");
  try {
    helix_holder_phantom(holder_named((dir / "unknown.json").string()));
    ADD_FAILURE() << "an unknown material was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("unobtainium"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("bar.stl"), std::string::npos) << e.what();
  }
}

TEST(TriangleMesh, AnOpenOrBadlyWoundMeshIsRefusedNamingItsFile) {
  const auto dir = testing::scratch_dir();
  auto triangles = box_triangles(1, 1, 1);
  triangles.pop_back();  // a hole
  write_binary(dir / "open.stl", triangles);
  auto flipped = box_triangles(1, 1, 1);
  std::swap(flipped[3][1], flipped[3][2]);  // one face wound the other way
  write_ascii(dir / "flipped.stl", flipped);
  testing::write_text(dir / "text.stl", "not an stl");
  for (const char* name : {"open.stl", "flipped.stl", "text.stl", "missing.stl"}) {
    try {
      TriangleMesh::read_stl(dir / name);
      ADD_FAILURE() << name << " accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  }
  // Wound inside out as a whole, it is turned: the same solid.
  auto inverted = box_triangles(2, 2, 2);
  for (auto& t : inverted) std::swap(t[1], t[2]);
  write_binary(dir / "inverted.stl", inverted);
  const TriangleMesh m = TriangleMesh::read_stl(dir / "inverted.stl");
  EXPECT_NEAR(m.volume_mm3(), 8, 1e-9);
  EXPECT_NEAR(m.chord_mm({-1, 1, 1}, {1, 0, 0}), 2, 1e-12);
}

}  // namespace
}  // namespace ctk
