// NRRD (teem.sourceforge.net/nrrd/format.html): a text header of "field: value" lines ended by
// an empty line, then the data (attached) or a "data file" field naming it (detached).
//
// Orientation: ctk's holder frame is written as NRRD's left-posterior-superior space, the world
// ITK works in, so ITK-based readers (3D Slicer, RTK, elastix) place every voxel where the
// MetaImage of the same volume puts it: at its holder-frame coordinates. A right-anterior-superior
// file (ITK negates its x and y) is read the way ITK reads it, with axes that run backwards
// reversed so that the voxel size stays positive; one that says it was written by ctk in that
// space (builds before this convention) is read in the holder frame it was written in.
#include <array>
#include <fstream>
#include <map>
#include <sstream>

#include "ctk/core/atomic_write.hpp"
#include "ctk/core/error.hpp"
#include "ctk/core/output_set.hpp"
#include "volume_formats.hpp"

namespace ctk::volume_formats {

namespace fs = std::filesystem;

namespace {

// The voxels with the axes marked reversed (index i becomes size - 1 - i).
void reverse_axes(Volume& v, const std::array<bool, 3>& reversed) {
  const Volume stored = v;
  const auto& n = v.layout.size;
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i)
        v.at(i, j, k) = stored.at(reversed[0] ? n[0] - 1 - i : i, reversed[1] ? n[1] - 1 - j : j, reversed[2] ? n[2] - 1 - k : k);
}

}  // namespace

void write_nrrd(const VolumeSlabs& v, const fs::path& file) {
  // Header and data in one file (NRRD's attached form): the file is written whole or not at all,
  // never a header over another run's data.
  const auto& l = v.layout;
  std::ostringstream h;
  h.precision(17);
  h << "NRRD0004\n# written by ctk (run " << this_run_id() << "): holder frame, millimetres\ntype: float\ndimension: 3\n"
    << "space: left-posterior-superior\n"
    << "sizes: " << l.size[0] << " " << l.size[1] << " " << l.size[2] << "\n"
    << "space directions: (" << l.voxel_mm.x() << ",0,0) (0," << l.voxel_mm.y() << ",0) (0,0," << l.voxel_mm.z() << ")\n"
    << "space origin: (" << l.origin_mm.x() << "," << l.origin_mm.y() << "," << l.origin_mm.z() << ")\n"
    << "kinds: domain domain domain\nendian: little\nencoding: raw\n\n";
  write_file_atomically(file, [&](std::ostream& out) {
    out << h.str();
    write_raw_slabs(v, out);
  });
}

// NOLINTNEXTLINE(readability-function-size): one header field per statement, each refused by its name
Volume read_nrrd(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::string line;
  if (!std::getline(in, line) || line.rfind("NRRD000", 0) != 0)
    throw InputError(file.string(), "line 1", "not a NRRD file (expected 'NRRD000<version>')");
  std::map<std::string, std::string> fields;
  bool written_by_ctk = false;
  int number = 1;
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) break;
    if (line[0] == '#') {
      written_by_ctk |= line.rfind("# written by ctk", 0) == 0;
      continue;
    }
    const std::size_t colon = line.find(": ");
    if (colon == std::string::npos) {
      if (line.find(":=") != std::string::npos) continue;  // key/value pairs: not needed
      throw InputError(file.string(), "line " + std::to_string(number), "expected 'field: value', got '" + line + "'");
    }
    fields[line.substr(0, colon)] = line.substr(colon + 2);
    if (number > 200) throw InputError(file.string(), "", "no end of the header in 200 lines");
  }
  auto field = [&](const std::string& key) -> const std::string& {
    const auto it = fields.find(key);
    if (it == fields.end()) throw InputError(file.string(), "field '" + key + "'", "missing");
    return it->second;
  };
  const std::string& type = field("type");
  if (type != "float" && type != "float32")
    throw InputError(file.string(), "field 'type'", "ctk reads float voxels, got '" + type + "'");
  if (field("dimension") != "3") throw InputError(file.string(), "field 'dimension'", "expected 3, got " + field("dimension"));
  if (field("encoding") != "raw")
    throw InputError(file.string(), "field 'encoding'", "ctk reads raw encoding, got '" + field("encoding") + "'");
  const auto endian = fields.find("endian");
  const bool big = endian != fields.end() && endian->second == "big";
  VolumeLayout l;
  const auto sizes = parse_numbers(field("sizes"), 3, file, "field 'sizes'");
  for (int a = 0; a < 3; ++a) l.size[static_cast<std::size_t>(a)] = static_cast<int>(sizes[static_cast<std::size_t>(a)]);
  // To the holder frame (= ITK's LPS world): the sign each axis of the file's space takes.
  Eigen::Vector3d to_holder{1, 1, 1};
  if (const auto space = fields.find("space"); space != fields.end()) {
    const std::string& name = space->second;
    const bool ras = name == "right-anterior-superior" || name == "RAS";
    const bool las = name == "left-anterior-superior" || name == "LAS";
    const bool lps = name == "left-posterior-superior" || name == "LPS";
    if (!ras && !las && !lps && name != "scanner-xyz" && name != "3D-right-handed")
      throw InputError(file.string(), "field 'space'",
                       "ctk reads the left-posterior-superior, right-anterior-superior, left-anterior-superior, scanner-xyz and "
                       "3D-right-handed spaces, got '" +
                           name + "'");
    if (ras && !written_by_ctk) to_holder = {-1, -1, 1};
    if (las) to_holder = {1, -1, 1};
  }
  Eigen::Vector3d step{1, 1, 1};  // signed voxel steps along the holder frame's axes
  if (fields.count("space directions")) {
    const auto d = parse_numbers(field("space directions"), 9, file, "field 'space directions'");
    for (std::size_t a = 0; a < 3; ++a)
      for (std::size_t b = 0; b < 3; ++b)
        if (a != b && d[3 * a + b] != 0)
          throw InputError(file.string(), "field 'space directions'",
                           "ctk reads axis-aligned voxels, got '" + field("space directions") + "'");
    step = Eigen::Vector3d(d[0], d[4], d[8]).cwiseProduct(to_holder);
  } else if (fields.count("spacings")) {
    step = parse_vector3(field("spacings"), file, "field 'spacings'");
  }
  l.voxel_mm = step.cwiseAbs();
  if (fields.count("space origin")) {
    l.origin_mm = parse_vector3(field("space origin"), file, "field 'space origin'").cwiseProduct(to_holder);
  } else {
    l.origin_mm = VolumeLayout::centred(l.size, l.voxel_mm).origin_mm;
  }
  // An axis that runs backwards is stored reversed: its first voxel is then the file's last.
  std::array<bool, 3> reversed{};
  for (int a = 0; a < 3; ++a) {
    reversed[static_cast<std::size_t>(a)] = step[a] < 0;
    if (step[a] < 0) l.origin_mm[a] += step[a] * (l.size[static_cast<std::size_t>(a)] - 1);
  }
  check_layout(l, file, "field 'sizes'");
  Volume v(l);
  const auto detached = fields.count("data file") ? fields.find("data file") : fields.find("datafile");
  if (detached != fields.end())
    read_raw_voxels(file.parent_path() / detached->second, 0, big, v);
  else
    read_raw_voxels(file, static_cast<std::uintmax_t>(in.tellg()), big, v);
  if (reversed[0] || reversed[1] || reversed[2]) reverse_axes(v, reversed);
  return v;
}

}  // namespace ctk::volume_formats
