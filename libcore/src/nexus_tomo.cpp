// NXtomo through the HDF Group's C library. Where the definition leaves a choice, readers in the
// field (CIL, tomwer) take the frames as [frames][rows][cols] and the angle in degrees; so does this.
#include "ctk/core/nexus_tomo.hpp"

#include <array>
#include <cmath>
#include <optional>
#include <utility>

#include "ctk/core/error.hpp"
#include "hdf5_handle.hpp"

namespace ctk {

namespace fs = std::filesystem;

using hdf5::Handle;

namespace {

enum class LinkKind { missing, inside, outside };

// Whether `path` names an object, and whether reaching it leaves the file: H5Lexists checks one
// link at a time, so every parent is asked for before its child; an external link on the way
// leads to another file (which may be a FIFO, or any file the reading user may read).
LinkKind find_link(hid_t location, const std::string& path) {
  std::size_t from = path.front() == '/' ? 1 : 0;
  while (true) {
    const std::size_t slash = path.find('/', from);
    const std::string prefix = path.substr(0, slash);
    if (H5Lexists(location, prefix.c_str(), H5P_DEFAULT) <= 0) return LinkKind::missing;
    H5L_info_t info{};
    if (H5Lget_info(location, prefix.c_str(), &info, H5P_DEFAULT) < 0 || info.type == H5L_TYPE_EXTERNAL ||
        info.type >= H5L_TYPE_UD_MIN)
      return LinkKind::outside;
    if (slash == std::string::npos) return LinkKind::inside;
    from = slash + 1;
  }
}

// What makes a dataset's values come from outside the file ("" when nothing does): external
// storage (raw data in other files) or a virtual dataset (views of other datasets, in other files
// or missing, then read as zeros).
std::string outside_storage(hid_t dataset) {
  const Handle plist(H5Dget_create_plist(dataset), H5Pclose);
  if (!plist.valid()) return "its storage cannot be read";
  if (H5Pget_external_count(plist.get()) > 0) return "its values are stored in other files (external storage)";
  if (H5Pget_layout(plist.get()) == H5D_VIRTUAL) return "it is a virtual dataset (its values come from other datasets)";
  return {};
}

// A string attribute or dataset, as any writer stores one (h5py's `str`: variable length, UTF-8;
// numpy's bytes: fixed length, null-padded, exactly as long as the text; C: null-terminated;
// Fortran: space-padded), or nothing when it is not one string. The memory type takes the file's
// character set (HDF5 converts no string between ASCII and UTF-8, so a UTF-8 `definition` read as
// ASCII was "no NXtomo entry") and one byte more than the file's size (a null-padded "mm" read
// into two null-terminated bytes lost its last character: a unit of "m").
// NXtomo's strings are names and units; a fixed size beyond this is a damaged or hostile file.
constexpr std::size_t kLongestString = 1 << 16;

std::optional<std::string> read_string(hid_t object, bool attribute) {
  const Handle type(attribute ? H5Aget_type(object) : H5Dget_type(object), H5Tclose);
  if (!type.valid() || H5Tget_class(type.get()) != H5T_STRING) return std::nullopt;
  const Handle space(attribute ? H5Aget_space(object) : H5Dget_space(object), H5Sclose);
  if (H5Sget_simple_extent_npoints(space.get()) != 1) return std::nullopt;
  const Handle memory(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_cset(memory.get(), H5Tget_cset(type.get()));
  auto read = [&](void* buffer) {
    return attribute ? H5Aread(object, memory.get(), buffer)
                     : H5Dread(object, memory.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, buffer);
  };
  std::string s;
  if (H5Tis_variable_str(type.get()) > 0) {
    char* value = nullptr;
    H5Tset_size(memory.get(), H5T_VARIABLE);
    const herr_t status = read(&value);
    if (status >= 0 && value) s = value;
    if (value) H5free_memory(value);
    if (status < 0) return std::nullopt;
  } else {
    const std::size_t size = H5Tget_size(type.get());
    if (size == 0 || size > kLongestString) return std::nullopt;  // a declared size, not what the file holds
    std::string buffer(size + 1, '\0');
    H5Tset_size(memory.get(), size + 1);
    H5Tset_strpad(memory.get(), H5T_STR_NULLTERM);
    if (read(buffer.data()) < 0) return std::nullopt;
    s = buffer.substr(0, buffer.find('\0'));
  }
  // Fortran's space padding, and the odd writer's trailing blank.
  s.erase(s.find_last_not_of(" \t\r\n") + 1);
  return s;
}

// An attribute's text: "" when there is none; nothing when it is there but not one string.
std::optional<std::string> string_attribute(hid_t object, const char* name) {
  if (H5Aexists(object, name) <= 0) return std::string();
  const Handle a(H5Aopen(object, name, H5P_DEFAULT), H5Aclose);
  return a.valid() ? read_string(a.get(), true) : std::nullopt;
}

class Reader {
 public:
  explicit Reader(const fs::path& file) : file_(file) {
    hdf5::quiet_library();
    require_regular_file(file);
    if (H5Fis_hdf5(file.c_str()) <= 0) throw InputError(file.string(), "", "not an HDF5 file (NXtomo is stored in HDF5)");
    h5_ = H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    if (h5_ < 0) throw InputError(file.string(), "", "cannot open the HDF5 file");
  }
  ~Reader() { H5Fclose(h5_); }
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;

  hid_t file() const { return h5_; }
  /// Whether `path` is in the file; refused when it, or a group on the way, is a link to another file.
  bool has(const std::string& path) const {
    const LinkKind kind = find_link(h5_, path);
    if (kind == LinkKind::outside)
      fail(path, "is, or lies behind, a link to another file; ctk reads an NXtomo file whole, without the files it links to");
    return kind == LinkKind::inside;
  }
  /// The dataset at `path`, refused unless its values are in this file.
  Handle dataset(const std::string& path) const {
    Handle d(H5Dopen2(h5_, path.c_str(), H5P_DEFAULT), H5Dclose);
    if (!d.valid()) fail(path, "cannot be opened");
    if (const std::string why = outside_storage(d.get()); !why.empty())
      fail(path, why + "; ctk reads an NXtomo file whole, without the files it refers to");
    return d;
  }
  [[noreturn]] void fail(const std::string& path, const std::string& what) const {
    throw InputError(file_.string(), "dataset '" + path + "'", what);
  }

  /// A string dataset's text; nothing when it is not one string.
  std::optional<std::string> string(const std::string& path) const { return read_string(dataset(path).get(), false); }

  // A one-dimensional numeric dataset (a scalar counts as one value) and its `units` attribute.
  // More than `most` values are refused before any is read: a small file may declare any count.
  std::vector<double> numbers(const std::string& path, std::size_t most, std::string* units = nullptr) const {
    const Handle d = dataset(path);
    const Handle type(H5Dget_type(d.get()), H5Tclose);
    const H5T_class_t c = H5Tget_class(type.get());
    if (c != H5T_INTEGER && c != H5T_FLOAT) fail(path, "expected numbers");
    const Handle space(H5Dget_space(d.get()), H5Sclose);
    if (H5Sget_simple_extent_ndims(space.get()) > 1) fail(path, "expected one value per frame (one dimension)");
    const hssize_t count = H5Sget_simple_extent_npoints(space.get());
    if (count < 0) fail(path, "cannot read its size");
    if (static_cast<std::size_t>(count) > most)
      fail(path, "declares " + std::to_string(count) + " values; expected at most " + std::to_string(most));
    std::vector<double> v(static_cast<std::size_t>(count));
    if (!v.empty() && H5Dread(d.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()) < 0)
      fail(path, "cannot read its values");
    for (double x : v)
      if (!std::isfinite(x)) fail(path, "holds a value that is not finite");
    if (units) {
      const std::optional<std::string> text = string_attribute(d.get(), "units");
      if (!text)
        throw InputError(file_.string(), "attribute 'units' of dataset '" + path + "'",
                         "expected one string (a unit such as mm)");
      *units = *text;
    }
    return v;
  }

 private:
  fs::path file_;
  hid_t h5_ = -1;
};

// mm per unit of a NeXus length, or 0 when the unit is not one this knows.
double mm_per(const std::string& unit) {
  if (unit == "m" || unit == "meter" || unit == "metre" || unit == "meters" || unit == "metres") return 1000;
  if (unit == "cm") return 10;
  if (unit == "mm" || unit == "millimeter" || unit == "millimetre") return 1;
  if (unit == "um" || unit == "micron" || unit == "microns" || unit == "micrometer" || unit == "micrometre" ||
      unit == "\xC2\xB5m")
    return 1e-3;
  if (unit == "nm") return 1e-6;
  return 0;
}

// The names of the links in a group (its members), in name order; none when it cannot be listed.
std::vector<std::string> member_names(hid_t group) {
  std::vector<std::string> names;
  H5G_info_t info{};
  if (H5Gget_info(group, &info) < 0) return names;
  for (hsize_t i = 0; i < info.nlinks; ++i) {
    const ssize_t n = H5Lget_name_by_idx(group, ".", H5_INDEX_NAME, H5_ITER_INC, i, nullptr, 0, H5P_DEFAULT);
    if (n <= 0) continue;
    std::string name(static_cast<std::size_t>(n) + 1, '\0');
    H5Lget_name_by_idx(group, ".", H5_INDEX_NAME, H5_ITER_INC, i, name.data(), name.size(), H5P_DEFAULT);
    name.resize(static_cast<std::size_t>(n));
    names.push_back(std::move(name));
  }
  return names;
}

// The first group at the root whose `definition` says NXtomo.
std::string find_entry(const Reader& r, const fs::path& file) {
  std::string unreadable;  // a definition that is not one string: named if no entry is found
  for (const std::string& name : member_names(r.file())) {
    const std::string definition = "/" + name + "/definition";
    if (!r.has(definition)) continue;
    const std::optional<std::string> text = r.string(definition);
    if (text == "NXtomo") return "/" + name;
    if (!text && unreadable.empty()) unreadable = definition;
  }
  if (!unreadable.empty())
    throw InputError(file.string(), "dataset '" + unreadable + "'",
                     "expected one string (NXtomo's entry says definition 'NXtomo'); no other group at the root says it");
  throw InputError(file.string(), "", "no group at the root has definition 'NXtomo' (name one with --entry)");
}

// A length in mm from a dataset with a `units` attribute; nothing (and a warning) without a unit.
std::optional<double> length_mm(const Reader& r, const std::string& path, NxTomo& scan) {
  if (!r.has(path)) return std::nullopt;
  std::string units;
  const std::vector<double> v = r.numbers(path, 1, &units);
  if (v.size() != 1) r.fail(path, "expected one value, got " + std::to_string(v.size()));
  const double scale = mm_per(units);
  if (scale == 0) {
    scan.warnings.push_back(path + " is ignored: its units attribute ('" + units + "') is not a length ctk knows");
    return std::nullopt;
  }
  return v.front() * scale;
}

// The NXsource group of the instrument (any name; "source" when no NX_class says so).
std::string find_source(const Reader& r, const std::string& instrument) {
  const Handle group(H5Gopen2(r.file(), instrument.c_str(), H5P_DEFAULT), H5Gclose);
  if (group.valid())
    for (const std::string& name : member_names(group.get())) {
      H5O_info_t object{};
      if (H5Oget_info_by_name(group.get(), name.c_str(), &object, H5P_DEFAULT) < 0 || object.type != H5O_TYPE_GROUP) continue;
      const Handle child(H5Gopen2(group.get(), name.c_str(), H5P_DEFAULT), H5Gclose);
      if (child.valid() && string_attribute(child.get(), "NX_class") == std::optional<std::string>("NXsource"))
        return instrument + "/" += name;
    }
  return instrument + "/source";
}

}  // namespace

std::vector<int> NxTomo::frames_of(NxFrameKind k) const {
  std::vector<int> out;
  for (int f = 0; f < frames; ++f)
    if (kind[static_cast<std::size_t>(f)] == k) out.push_back(f);
  return out;
}

// NOLINTNEXTLINE(readability-function-size): one field per statement, each refused by its name
NxTomo read_nxtomo(const fs::path& file, const std::string& entry_name) {
  const Reader r(file);
  NxTomo scan;
  scan.file = file;
  scan.entry = entry_name.empty() ? find_entry(r, file) : (entry_name.front() == '/' ? entry_name : "/" + entry_name);
  if (!r.has(scan.entry)) throw InputError(file.string(), "group '" + scan.entry + "'", "missing");
  const std::string detector = scan.entry + "/instrument/detector";
  scan.data_path = r.has(detector + "/data") ? detector + "/data" : scan.entry + "/data/data";
  if (!r.has(scan.data_path)) r.fail(detector + "/data", "missing: NXtomo keeps its frames there");
  {
    const Handle d = r.dataset(scan.data_path);
    const Handle space(H5Dget_space(d.get()), H5Sclose);
    const Handle type(H5Dget_type(d.get()), H5Tclose);
    if (!d.valid() || H5Sget_simple_extent_ndims(space.get()) != 3)
      r.fail(scan.data_path, "expected three dimensions (frames, rows, columns)");
    const H5T_class_t c = H5Tget_class(type.get());
    if (c != H5T_INTEGER && c != H5T_FLOAT) r.fail(scan.data_path, "expected numbers (integer counts or floats)");
    scan.integer_data = c == H5T_INTEGER;
    std::array<hsize_t, 3> dims{};
    H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
    for (hsize_t n : dims)
      if (n == 0 || n > (1u << 30)) r.fail(scan.data_path, "has an empty or implausibly large dimension");
    // A small file may declare any size; what it stores bounds what it can hold, before a frame
    // is allocated or written (a 15 KB file declaring 200,000 frames).
    const Handle plist(H5Dget_create_plist(d.get()), H5Pclose);
    const hsize_t stored = H5Dget_storage_size(d.get());
    const auto declared = static_cast<double>(dims[0]) * static_cast<double>(dims[1]) * static_cast<double>(dims[2]) *
                          static_cast<double>(H5Tget_size(type.get()));
    if (stored == 0) r.fail(scan.data_path, "stores no values (declared, never written)");
    if (H5Pget_layout(plist.get()) == H5D_CHUNKED) {
      // Chunks never written read as the fill value: frames nobody measured.
      std::array<hsize_t, 3> chunk{};
      hsize_t allocated = 0;
      if (H5Pget_chunk(plist.get(), 3, chunk.data()) == 3 && H5Dget_num_chunks(d.get(), space.get(), &allocated) >= 0) {
        double total = 1;
        for (std::size_t a = 0; a < 3; ++a)
          total *= std::ceil(static_cast<double>(dims[a]) / static_cast<double>(std::max<hsize_t>(chunk[a], 1)));
        if (static_cast<double>(allocated) < total)
          r.fail(scan.data_path, "stores " + std::to_string(allocated) + " of its " +
                                     std::to_string(static_cast<long long>(total)) +
                                     " chunks; the rest were declared and never written");
      }
    }
    if (H5Pget_layout(plist.get()) == H5D_CONTIGUOUS && static_cast<double>(stored) < declared)
      r.fail(scan.data_path, "declares " + std::to_string(dims[0]) + " x " + std::to_string(dims[1]) + " x " +
                                 std::to_string(dims[2]) + " values but stores " + std::to_string(stored) + " bytes");
    scan.frames = static_cast<int>(dims[0]);
    scan.rows = static_cast<int>(dims[1]);
    scan.cols = static_cast<int>(dims[2]);
  }
  const std::size_t frames = static_cast<std::size_t>(scan.frames);

  const std::string key_path = detector + "/image_key";
  if (r.has(key_path)) {
    for (double k : r.numbers(key_path, frames)) {
      if (k != 0 && k != 1 && k != 2 && k != 3)
        r.fail(key_path, "expected 0 (projection), 1 (flat), 2 (dark) or 3 (invalid), got " + std::to_string(k));
      scan.kind.push_back(static_cast<NxFrameKind>(static_cast<int>(k)));
    }
    if (scan.kind.size() != frames)
      r.fail(key_path, std::to_string(scan.kind.size()) + " keys for " + std::to_string(frames) + " frames");
  } else {
    scan.kind.assign(frames, NxFrameKind::projection);
    scan.warnings.push_back(key_path + " is missing: every frame taken as a projection");
  }

  std::string angle_path = scan.entry + "/sample/rotation_angle";
  if (!r.has(angle_path)) angle_path = scan.entry + "/data/rotation_angle";
  if (!r.has(angle_path))
    r.fail(scan.entry + "/sample/rotation_angle", "missing: NXtomo gives each frame's rotation angle there");
  std::string units;
  scan.rotation_angle_deg = r.numbers(angle_path, frames, &units);
  if (scan.rotation_angle_deg.size() != frames)
    r.fail(angle_path, std::to_string(scan.rotation_angle_deg.size()) + " angles for " + std::to_string(frames) + " frames");
  if (units == "rad" || units == "radian" || units == "radians") {
    for (double& a : scan.rotation_angle_deg) a *= 180.0 / M_PI;
  } else if (units.empty()) {
    scan.warnings.push_back(angle_path + " has no units attribute: taken in degrees");
  } else if (units != "deg" && units != "degree" && units != "degrees") {
    r.fail(angle_path, "units '" + units + "': expected degree or rad");
  }

  scan.x_pixel_size_mm = length_mm(r, detector + "/x_pixel_size", scan);
  scan.y_pixel_size_mm = length_mm(r, detector + "/y_pixel_size", scan);
  scan.sample_to_detector_mm = length_mm(r, detector + "/distance", scan);
  if (const auto d = length_mm(r, find_source(r, scan.entry + "/instrument") + "/distance", scan))
    scan.source_to_sample_mm = std::abs(*d);
  for (const auto* d : {&scan.x_pixel_size_mm, &scan.y_pixel_size_mm})
    if (*d && !(**d > 0))
      r.fail(detector + (d == &scan.x_pixel_size_mm ? "/x_pixel_size" : "/y_pixel_size"), "expected a size above 0");
  return scan;
}

struct NxTomoFrames::Open {
  explicit Open(const NxTomo& scan)
      : file(scan.file),
        data(H5Dopen2(file.file(), scan.data_path.c_str(), H5P_DEFAULT), H5Dclose),
        space(H5Dget_space(data.get()), H5Sclose),
        memory(
            H5Screate_simple(
                3, std::array<hsize_t, 3>{1, static_cast<hsize_t>(scan.rows), static_cast<hsize_t>(scan.cols)}.data(), nullptr),
            H5Sclose) {
    if (!data.valid() || !space.valid()) file.fail(scan.data_path, "cannot be opened");
  }
  Reader file;
  Handle data, space, memory;
};

NxTomoFrames::NxTomoFrames(const NxTomo& scan) : scan_(scan), open_(std::make_unique<Open>(scan)) {}

NxTomoFrames::~NxTomoFrames() = default;

Image NxTomoFrames::read(int frame) const {
  const NxTomo& scan = scan_;
  if (frame < 0 || frame >= scan.frames) open_->file.fail(scan.data_path, "has no frame " + std::to_string(frame));
  const std::array<hsize_t, 3> start{static_cast<hsize_t>(frame), 0, 0},
      count{1, static_cast<hsize_t>(scan.rows), static_cast<hsize_t>(scan.cols)};
  Image image{scan.cols, scan.rows,
              std::vector<float>(static_cast<std::size_t>(scan.rows) * static_cast<std::size_t>(scan.cols))};
  if (H5Sselect_hyperslab(open_->space.get(), H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr) < 0 ||
      H5Dread(open_->data.get(), H5T_NATIVE_FLOAT, open_->memory.get(), open_->space.get(), H5P_DEFAULT, image.pixels.data()) < 0)
    open_->file.fail(scan.data_path, "cannot read frame " + std::to_string(frame));
  return image;
}

}  // namespace ctk
