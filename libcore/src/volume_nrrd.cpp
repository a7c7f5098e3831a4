// NRRD (teem.sourceforge.net/nrrd/format.html): a text header of "field: value" lines ended by
// an empty line, then the data (attached) or a "data file" field naming it (detached).
#include <fstream>
#include <map>
#include <sstream>

#include "ctk/core/atomic_write.hpp"
#include "ctk/core/error.hpp"
#include "ctk/core/output_set.hpp"
#include "volume_formats.hpp"

namespace ctk::volume_formats {

namespace fs = std::filesystem;

void write_nrrd(const VolumeSlabs& v, const fs::path& file) {
  // Header and data in one file (NRRD's attached form): the file is written whole or not at all,
  // never a header over another run's data.
  const auto& l = v.layout;
  std::ostringstream h;
  h.precision(17);
  h << "NRRD0004\n# written by ctk (run " << this_run_id() << "): holder frame, millimetres\ntype: float\ndimension: 3\n"
    << "space: right-anterior-superior\n"
    << "sizes: " << l.size[0] << " " << l.size[1] << " " << l.size[2] << "\n"
    << "space directions: (" << l.voxel_mm.x() << ",0,0) (0," << l.voxel_mm.y() << ",0) (0,0," << l.voxel_mm.z() << ")\n"
    << "space origin: (" << l.origin_mm.x() << "," << l.origin_mm.y() << "," << l.origin_mm.z() << ")\n"
    << "kinds: domain domain domain\nendian: little\nencoding: raw\n\n";
  write_file_atomically(file, [&](std::ostream& out) {
    out << h.str();
    write_raw_slabs(v, out);
  });
}

Volume read_nrrd(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::string line;
  if (!std::getline(in, line) || line.rfind("NRRD000", 0) != 0)
    throw InputError(file.string(), "line 1", "not a NRRD file (expected 'NRRD000<version>')");
  std::map<std::string, std::string> fields;
  int number = 1;
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) break;
    if (line[0] == '#') continue;
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
  if (fields.count("space directions")) {
    const auto d = parse_numbers(field("space directions"), 9, file, "field 'space directions'");
    for (std::size_t a = 0; a < 3; ++a)
      for (std::size_t b = 0; b < 3; ++b)
        if (a != b && d[3 * a + b] != 0)
          throw InputError(file.string(), "field 'space directions'",
                           "ctk reads axis-aligned voxels, got '" + field("space directions") + "'");
    l.voxel_mm = {d[0], d[4], d[8]};
  } else if (fields.count("spacings")) {
    l.voxel_mm = parse_vector3(field("spacings"), file, "field 'spacings'");
  }
  if (fields.count("space origin")) {
    l.origin_mm = parse_vector3(field("space origin"), file, "field 'space origin'");
  } else {
    l.origin_mm = VolumeLayout::centred(l.size, l.voxel_mm).origin_mm;
  }
  check_layout(l, file, "field 'sizes'");
  Volume v(l);
  const auto detached = fields.count("data file") ? fields.find("data file") : fields.find("datafile");
  if (detached != fields.end())
    read_raw_voxels(file.parent_path() / detached->second, 0, big, v);
  else
    read_raw_voxels(file, static_cast<std::uintmax_t>(in.tellg()), big, v);
  return v;
}

}  // namespace ctk::volume_formats
