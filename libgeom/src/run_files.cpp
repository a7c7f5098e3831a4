#include "ctk/geom/run_files.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <map>
#include <set>
#include <utility>

#include "ctk/core/atomic_write.hpp"
#include "ctk/core/error.hpp"
#include "ctk/core/output_set.hpp"
#include "ctk/geom/scan.hpp"

namespace ctk {

namespace fs = std::filesystem;

namespace {

fs::path place_of(const fs::path& p) {
  std::error_code ec;
  fs::path resolved = fs::weakly_canonical(fs::absolute(p, ec), ec);
  return ec ? fs::absolute(p).lexically_normal() : resolved;
}

// The same file under another name (a hard link): device and inode.
std::pair<dev_t, ino_t> identity(const fs::path& p, bool& exists) {
  struct stat s {};
  exists = ::stat(p.c_str(), &s) == 0;
  return {s.st_dev, s.st_ino};
}

bool inside(const fs::path& file, const fs::path& folder) {
  auto f = file.begin();
  for (auto d = folder.begin(); d != folder.end(); ++d, ++f) {
    if (d->empty()) continue;  // a trailing separator
    if (f == file.end() || *f != *d) return false;
  }
  return true;
}

bool starts_and_ends(const std::string& s, const std::string& prefix, const std::string& suffix) {
  return s.size() >= prefix.size() + suffix.size() && s.compare(0, prefix.size(), prefix) == 0 &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::string named(const std::string& what, const fs::path& p) { return what + " (" + p.string() + ")"; }

// The folder an output goes into, or the nearest of its parents that exists, must take new files:
// a run that can only write its results after an hour's solve is told before it starts. Asked by
// creating (and removing) a file there: permission bits do not tell root about a read-only mount,
// nor anyone about a file system such as /proc.
std::string not_writable(const fs::path& place, std::map<fs::path, std::string>& asked) {
  fs::path folder = place.parent_path();
  std::error_code ec;
  while (!folder.empty() && !fs::exists(folder, ec)) {
    if (folder == folder.parent_path()) break;
    folder = folder.parent_path();
  }
  if (folder.empty()) folder = ".";
  if (const auto it = asked.find(folder); it != asked.end()) return it->second;  // one probe per folder
  std::string& answer = asked[folder];
  if (!fs::is_directory(folder, ec)) return answer = folder.string() + " is not a folder";
  const fs::path probe = temporary_beside(folder / ".ctk-probe");
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) return answer = "the folder " + folder.string() + " does not take new files (" + std::strerror(errno) + ")";
  ::close(fd);
  ::unlink(probe.c_str());
  return {};
}

}  // namespace

void RunFiles::input(std::string what, const fs::path& file) {
  if (!file.empty()) inputs_.push_back({std::move(what), file, place_of(file), ""});
}

void RunFiles::scan(const std::string& what, const fs::path& scan_file, const ScanDescription& s) {
  input(what, scan_file);
  for (int v = 0; v < s.projections.count; ++v) input(what + ": projection " + std::to_string(v), s.projection_path(v));
  for (const std::string& f : s.projections.flat) input(what + ": projections.flat", s.resolve(f));
  for (const std::string& d : s.projections.dark) input(what + ": projections.dark", s.resolve(d));
  if (s.panda) input(what + ": pose_source.joints_csv", s.resolve(s.panda->joints_csv));
  if (s.matrices) input(what + ": pose_source.file", s.resolve(s.matrices->file));
}

void RunFiles::scan_to_read(const std::string& what, const fs::path& scan_file, const ScanDescription& s) {
  require_projection_files(s, scan_file.string(), "projections.count");
  scan(what, scan_file, s);
}

void RunFiles::input_folder(std::string what, const fs::path& folder) {
  if (!folder.empty()) input_folders_.push_back({std::move(what), folder, place_of(folder), ""});
}

void RunFiles::output(std::string what, const fs::path& file) {
  if (!file.empty()) outputs_.push_back({std::move(what), file, place_of(file), ""});
}

void RunFiles::output_folder(std::string what, const fs::path& folder) {
  if (!folder.empty()) output_folders_.push_back({std::move(what), folder, place_of(folder), ""});
}

void RunFiles::output_family(std::string what, const fs::path& prefix, const std::string& suffix) {
  // The prefix's folder is resolved; its last part is a name's beginning, kept as given.
  const fs::path folder = place_of(prefix.has_parent_path() ? prefix.parent_path() : fs::path("."));
  families_.push_back({std::move(what), prefix, folder / prefix.filename(), suffix});
}

void RunFiles::check() const {
  auto refuse = [](const Entry& out, const std::string& what) {
    throw InputError(out.path.string(), out.what, "would overwrite " + what + "; name another output");
  };
  std::map<fs::path, const Entry*> by_place;
  std::map<std::pair<dev_t, ino_t>, const Entry*> by_identity;
  for (const Entry& in : inputs_) {
    by_place.emplace(in.place, &in);
    bool exists = false;
    const auto id = identity(in.place, exists);
    if (exists) by_identity.emplace(id, &in);
  }
  std::map<fs::path, const Entry*> written;
  std::map<fs::path, std::string> probed;  // folders asked whether they take new files, and the answer
  for (const Entry& out : outputs_) {
    if (const std::string why = not_an_output_name(out.path); !why.empty()) throw InputError(out.path.string(), out.what, why);
    if (const std::string kind = not_replaceable_by_output(out.path); !kind.empty())
      throw InputError(out.path.string(), out.what,
                       "is " + kind + ", not a regular file; ctk replaces its outputs whole, so it names only files");
    if (const std::string why = not_writable(out.place, probed); !why.empty())
      throw InputError(out.path.string(), out.what, "cannot be written: " + why);
    if (const auto it = by_place.find(out.place); it != by_place.end())
      refuse(out, "the input " + named(it->second->what, it->second->path));
    bool exists = false;
    const auto id = identity(out.place, exists);
    if (exists)
      if (const auto it = by_identity.find(id); it != by_identity.end())
        refuse(out, "the input " + named(it->second->what, it->second->path) + ", the same file under another name");
    for (const Entry& folder : input_folders_)
      if (inside(out.place, folder.place)) refuse(out, "a file in the input folder " + named(folder.what, folder.path));
    if (const auto [it, added] = written.emplace(out.place, &out); !added)
      refuse(out, "the output " + named(it->second->what, it->second->path) + " of the same run");
  }
  for (const Entry& folder : output_folders_) {
    if (std::error_code ec; fs::exists(folder.path, ec) && !fs::is_directory(folder.path, ec))
      throw InputError(folder.path.string(), folder.what, "is not a folder; the run writes its files into a folder there");
    if (const std::string why = not_writable(folder.place / ".", probed); !why.empty())
      throw InputError(folder.path.string(), folder.what, "cannot be written: " + why);
    for (const Entry& in : inputs_)
      if (inside(in.place, folder.place)) refuse(folder, "the input " + named(in.what, in.path) + ", which lies in it");
    for (const Entry& in : input_folders_)
      if (inside(in.place, folder.place) || inside(folder.place, in.place))
        refuse(folder, "files of the input folder " + named(in.what, in.path));
  }
  for (const Entry& family : families_) {
    const std::string prefix = family.place.string();
    for (const Entry& in : inputs_)
      if (starts_and_ends(in.place.string(), prefix, family.suffix))
        refuse(family,
               "the input " + named(in.what, in.path) + " (it writes " + family.path.string() + "*" + family.suffix + ")");
    for (const Entry& out : outputs_)
      if (starts_and_ends(out.place.string(), prefix, family.suffix))
        refuse(out, "a file of " + named(family.what, fs::path(family.path.string() + "*" + family.suffix)) + " of the same run");
  }
}

}  // namespace ctk
