// MetaImage (ITK's .mha/.mhd): "Key = Value" lines, ElementDataFile last; LOCAL means the data
// follows the header in the same file, otherwise it names the data file beside the header.
#include <fstream>
#include <map>
#include <sstream>

#include "ctk/core/atomic_write.hpp"
#include "ctk/core/error.hpp"
#include "volume_formats.hpp"

namespace ctk::volume_formats {

namespace fs = std::filesystem;

void write_metaimage(const VolumeSlabs& v, const fs::path& file, bool detached) {
  const auto& l = v.layout;
  const fs::path raw = fs::path(file).replace_extension(".raw");
  std::ostringstream h;
  h.precision(17);
  h << "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\nCompressedData = False\n"
    << "TransformMatrix = 1 0 0 0 1 0 0 0 1\n"
    << "Offset = " << l.origin_mm.x() << " " << l.origin_mm.y() << " " << l.origin_mm.z() << "\n"
    << "ElementSpacing = " << l.voxel_mm.x() << " " << l.voxel_mm.y() << " " << l.voxel_mm.z() << "\n"
    << "DimSize = " << l.size[0] << " " << l.size[1] << " " << l.size[2] << "\n"
    << "ElementType = MET_FLOAT\nElementDataFile = " << (detached ? raw.filename().string() : "LOCAL") << "\n";
  const auto voxels = [&](std::ostream& out) { write_raw_slabs(v, out); };
  if (detached) {
    write_file_atomically(raw, voxels);  // the data first: a header never names data not yet there
    write_text_atomically(file, h.str());
  } else {
    write_file_atomically(file, [&](std::ostream& out) {
      out << h.str();
      voxels(out);
    });
  }
}

Volume read_metaimage(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::map<std::string, std::string> fields;
  std::string line;
  int number = 0;
  auto trim = [](const std::string& s) {
    const auto first = s.find_first_not_of(" \t\r"), last = s.find_last_not_of(" \t\r");
    return first == std::string::npos ? std::string() : s.substr(first, last - first + 1);
  };
  while (std::getline(in, line)) {
    ++number;
    const std::size_t equals = line.find('=');
    if (equals == std::string::npos)
      throw InputError(file.string(), "line " + std::to_string(number), "expected 'Key = Value', got '" + trim(line) + "'");
    const std::string key = trim(line.substr(0, equals)), value = trim(line.substr(equals + 1));
    fields[key] = value;
    if (key == "ElementDataFile") break;
    if (number > 200) throw InputError(file.string(), "", "no ElementDataFile in the first 200 lines: not a MetaImage header");
  }
  auto field = [&](const std::string& key) -> const std::string& {
    const auto it = fields.find(key);
    if (it == fields.end()) throw InputError(file.string(), "key '" + key + "'", "missing");
    return it->second;
  };
  auto either = [&](const char* a, const char* b) { return fields.count(a) ? std::string(a) : std::string(b); };
  if (field("NDims") != "3") throw InputError(file.string(), "key 'NDims'", "expected 3, got " + field("NDims"));
  if (field("ElementType") != "MET_FLOAT")
    throw InputError(file.string(), "key 'ElementType'", "ctk reads MET_FLOAT voxels, got " + field("ElementType"));
  if (fields.count("CompressedData") && fields["CompressedData"] != "False")
    throw InputError(file.string(), "key 'CompressedData'", "ctk reads uncompressed data");
  if (fields.count("ElementNumberOfChannels") && fields["ElementNumberOfChannels"] != "1")
    throw InputError(file.string(), "key 'ElementNumberOfChannels'", "expected 1");
  if (fields.count("TransformMatrix")) {
    const auto m = parse_numbers(fields["TransformMatrix"], 9, file, "key 'TransformMatrix'");
    for (int a = 0; a < 9; ++a)
      if (m[static_cast<std::size_t>(a)] != (a % 4 == 0 ? 1.0 : 0.0))
        throw InputError(file.string(), "key 'TransformMatrix'",
                         "ctk reads axis-aligned volumes (identity), got '" + fields["TransformMatrix"] + "'");
  }
  const std::string order = either("BinaryDataByteOrderMSB", "ElementByteOrderMSB");
  const bool big = fields.count(order) && fields[order] == "True";
  VolumeLayout l;
  const auto sizes = parse_numbers(field("DimSize"), 3, file, "key 'DimSize'");
  for (int a = 0; a < 3; ++a) l.size[static_cast<std::size_t>(a)] = static_cast<int>(sizes[static_cast<std::size_t>(a)]);
  const std::string spacing = either("ElementSpacing", "ElementSize");
  if (fields.count(spacing)) {
    l.voxel_mm = parse_vector3(fields[spacing], file, "key '" + spacing + "'");
  }
  const std::string origin = fields.count("Offset") ? "Offset" : either("Origin", "Position");
  if (fields.count(origin)) {
    l.origin_mm = parse_vector3(fields[origin], file, "key '" + origin + "'");
  } else {
    l.origin_mm = VolumeLayout::centred(l.size, l.voxel_mm).origin_mm;
  }
  check_layout(l, file, "key 'DimSize'");
  Volume v(l);
  const std::string& data = field("ElementDataFile");
  if (data == "LOCAL")
    read_raw_voxels(file, static_cast<std::uintmax_t>(in.tellg()), big, v);
  else
    read_raw_voxels(file.parent_path() / data, 0, big, v);
  return v;
}

}  // namespace ctk::volume_formats
