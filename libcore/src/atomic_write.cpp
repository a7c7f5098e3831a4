#include "ctk/core/atomic_write.hpp"

#include <fstream>
#include <stdexcept>

#include "ctk/core/error.hpp"
#include "ctk/core/output_set.hpp"

namespace ctk {

namespace fs = std::filesystem;

void write_path_atomically(const fs::path& path, const std::function<void(const fs::path&)>& write) {
  // The rename below would put a regular file where a device, a FIFO or a folder was.
  std::error_code ec;
  const fs::file_type existing = fs::status(path, ec).type();
  if (!ec && existing != fs::file_type::not_found && existing != fs::file_type::regular)
    throw InputError(path.string(), "",
                     "exists and is not a regular file; an output replaces a file whole, so it names only files");
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
