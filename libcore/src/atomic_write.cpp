#include "ctk/core/atomic_write.hpp"

#include <fstream>
#include <stdexcept>

#include "ctk/core/error.hpp"
#include "ctk/core/output_set.hpp"

namespace ctk {

namespace fs = std::filesystem;

std::string not_replaceable_by_output(const fs::path& path) {
  std::error_code ec;
  switch (fs::status(path, ec).type()) {  // through symbolic links: what the name leads to
    case fs::file_type::not_found:
    case fs::file_type::regular:
      return {};
    case fs::file_type::directory:
      return "a folder";
    case fs::file_type::character:
    case fs::file_type::block:
      return "a device";
    case fs::file_type::fifo:
      return "a FIFO";
    case fs::file_type::socket:
      return "a socket";
    default:
      return ec ? std::string() : std::string("not a regular file");
  }
}

std::string not_an_output_name(const fs::path& path) {
  const std::string name = path.filename().string();
  if (name.empty() || name == "." || name == "..") return "names no file (an empty name, or a folder)";
  if (name.size() > 255) return "a name of " + std::to_string(name.size()) + " bytes; file systems take at most 255 per name";
  return {};
}

void write_path_atomically(const fs::path& path, const std::function<void(const fs::path&)>& write) {
  if (const std::string why = not_an_output_name(path); !why.empty()) throw InputError(path.string(), "", why);
  if (const std::string kind = not_replaceable_by_output(path); !kind.empty())
    throw InputError(path.string(), "",
                     "is " + kind + ", not a regular file; an output replaces a file whole, so it names only files");
  if (path.has_parent_path()) fs::create_directories(path.parent_path());
  const fs::path tmp = temporary_beside(path);
  try {
    write(tmp);
    if (OutputSet* set = OutputSet::active())
      set->add(tmp, path);  // renamed with the rest of the run's outputs
    else
      fs::rename(tmp, path);
  } catch (...) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw;
  }
}

void write_file_atomically(const fs::path& path, const std::function<void(std::ostream&)>& write) {
  write_path_atomically(path, [&](const fs::path& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) throw std::runtime_error(path.string() + ": cannot open for writing");
    write(out);
    out.flush();
    if (!out) throw std::runtime_error(path.string() + ": write failed (disk full?)");
  });
}

void write_text_atomically(const fs::path& path, std::string_view text) {
  write_file_atomically(path, [&](std::ostream& out) { out.write(text.data(), static_cast<std::streamsize>(text.size())); });
}

}  // namespace ctk
