#include "ctk/core/file_names.hpp"

#include <fnmatch.h>

#include <algorithm>
#include <cctype>

#include "ctk/core/error.hpp"

namespace ctk {

namespace fs = std::filesystem;

namespace {
bool digit(char c) { return std::isdigit(static_cast<unsigned char>(c)) != 0; }
}  // namespace

bool natural_less(const std::string& a, const std::string& b) {
  std::size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (digit(a[i]) && digit(b[j])) {
      std::size_t ie = i, je = j;
      while (ie < a.size() && digit(a[ie])) ++ie;
      while (je < b.size() && digit(b[je])) ++je;
      // Compare values without overflow: strip leading zeros, then the longer run is larger.
      std::size_t iz = i, jz = j;
      while (iz + 1 < ie && a[iz] == '0') ++iz;
      while (jz + 1 < je && b[jz] == '0') ++jz;
      const std::string_view x(a.data() + iz, ie - iz), y(b.data() + jz, je - jz);
      if (x.size() != y.size()) return x.size() < y.size();
      if (x != y) return x < y;
      if (ie - i != je - j) return ie - i < je - j;
      i = ie;
      j = je;
    } else {
      if (a[i] != b[j]) return a[i] < b[j];
      ++i;
      ++j;
    }
  }
  return a.size() - i < b.size() - j;
}

bool is_glob(const std::string& path) { return fs::path(path).filename().string().find_first_of("*?[") != std::string::npos; }

std::vector<fs::path> matching_files(const fs::path& folder, const std::string& pattern) {
  const fs::path where = folder.empty() ? fs::path(".") : folder;
  std::error_code ec;
  fs::directory_iterator it(where, ec);
  if (ec) throw InputError(where.string(), "", "cannot list the folder: " + ec.message());
  std::vector<std::string> names;
  for (const fs::directory_entry& e : it) {
    const std::string name = e.path().filename().string();
    if (e.is_regular_file(ec) && fnmatch(pattern.c_str(), name.c_str(), FNM_PERIOD) == 0) names.push_back(name);
  }
  std::sort(names.begin(), names.end(), natural_less);
  std::vector<fs::path> out;
  out.reserve(names.size());
  for (const std::string& n : names) out.push_back(folder / n);
  return out;
}

}  // namespace ctk
