#include "ctk/core/output_set.hpp"

#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <random>
#include <stdexcept>

#include "ctk/core/cancellation.hpp"

namespace ctk {

namespace fs = std::filesystem;

namespace {

std::atomic<OutputSet*> active_set{nullptr};

// This host's name as run ids carry it.
std::string host_name() {
  char host[256] = "host";
  ::gethostname(host, sizeof host - 1);
  std::string id = host;
  for (char& c : id)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-') c = '-';
  return id;
}

// Temporaries beside `target` left by runs of this host that were killed (their process is gone):
// a kill -9 runs no clean-up, so the next run writing the same target does it.
void remove_stale_temporaries(const fs::path& target) {
  const fs::path folder = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::string prefix = ".";  // piece by piece: GCC 12 misreads "." + std::string (-Wrestrict)
  prefix += target.stem().string();
  prefix += ".";
  prefix += host_name();
  prefix += "-";
  std::error_code ec;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.compare(0, prefix.size(), prefix) != 0) continue;
    const long pid = std::strtol(name.c_str() + prefix.size(), nullptr, 10);
    if (pid <= 0 || pid == ::getpid() || ::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH) continue;
    std::error_code ignored;
    fs::remove_all(entry.path(), ignored);
  }
}

std::string make_run_id() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  ::gmtime_r(&now, &utc);
  char when[32];
  std::strftime(when, sizeof when, "%Y%m%dT%H%M%S", &utc);
  std::random_device entropy;
  const unsigned random = entropy();
  char tail[16];
  std::snprintf(tail, sizeof tail, "%08x", random);
  return host_name() + "-" + std::to_string(::getpid()) + "-" + when + "-" + tail;
}

}  // namespace

const std::string& this_run_id() {
  static const std::string id = make_run_id();
  return id;
}

fs::path temporary_beside(const fs::path& path) {
  static std::atomic<unsigned> counter{0};
  // Appended piece by piece: GCC 12 misreads "." + std::string as an overlapping copy (-Wrestrict).
  std::string tail = ".";
  tail += this_run_id();
  tail += "-";
  tail += std::to_string(counter++);
  // A file system takes names of up to NAME_MAX (255) bytes: the stem gives way to the run's id,
  // so that an output of a legal name always has a legal temporary beside it.
  const std::string stem = path.stem().string(), extension = path.extension().string();
  const std::size_t room = 255 - std::min<std::size_t>(255, 1 + tail.size() + extension.size());
  std::string name = ".";
  name += stem.substr(0, room);
  name += tail;
  name += extension;
  fs::path tmp = path;
  tmp.replace_filename(name);
  return tmp;
}

OutputSet::OutputSet() {
  OutputSet* none = nullptr;
  if (!active_set.compare_exchange_strong(none, this)) throw std::logic_error("OutputSet: another set is active");
}

OutputSet::~OutputSet() {
  active_set = nullptr;
  std::error_code ignored;
  for (const auto& [temporary, target] : waiting_) fs::remove(temporary, ignored);
  folders_.clear();  // each unpublished folder's hidden folder removed
}

OutputSet* OutputSet::active() { return active_set.load(); }

OutputSet::Outside::Outside() : held_(active_set.exchange(nullptr)) {}
OutputSet::Outside::~Outside() { active_set = held_; }

void OutputSet::add(fs::path temporary, fs::path target) {
  const std::lock_guard lock(mutex_);
  // A file written again replaces its earlier version in the queue, at its new place in the order.
  const auto earlier = std::find_if(waiting_.begin(), waiting_.end(), [&](const auto& w) { return w.second == target; });
  if (earlier != waiting_.end()) {
    std::error_code ignored;
    fs::remove(earlier->first, ignored);
    waiting_.erase(earlier);
  }
  waiting_.emplace_back(std::move(temporary), std::move(target));
}

fs::path OutputSet::current(const fs::path& target) {
  const std::lock_guard lock(mutex_);
  for (auto it = waiting_.rbegin(); it != waiting_.rend(); ++it)
    if (it->second == target) return it->first;
  return target;
}

void OutputSet::add(std::unique_ptr<StagedFolder> folder) {
  const std::lock_guard lock(mutex_);
  folders_.push_back(std::move(folder));
}

void commit_with_outputs(std::unique_ptr<StagedFolder> folder) {
  if (OutputSet* outputs = OutputSet::active())
    outputs->add(std::move(folder));
  else
    folder->commit();
}

void OutputSet::publish() {
  throw_if_stop_requested_before_publishing();
  const std::lock_guard lock(mutex_);
  for (const std::unique_ptr<StagedFolder>& folder : folders_) folder->swap_in();
  folders_.clear();
  for (auto it = waiting_.begin(); it != waiting_.end(); it = waiting_.erase(it)) {
    fs::rename(it->first, it->second);
    remove_stale_temporaries(it->second);
  }
}

StagedFolder::StagedFolder(fs::path target, std::vector<std::string> owned)
    : target_(std::move(target)), owned_(std::move(owned)) {
  // A target that is a symbolic link to a folder: the folder is replaced (beside it, on its file
  // system), the link stays.
  const fs::path absolute = fs::weakly_canonical(fs::absolute(target_));
  const fs::path parent = (absolute.filename().empty() ? absolute.parent_path() : absolute).parent_path();
  fs::create_directories(parent);
  place_ = parent / (absolute.filename().empty() ? absolute.parent_path().filename() : absolute.filename());
  remove_stale_temporaries(place_);
  staging_ = temporary_beside(place_);
  fs::create_directory(staging_);
}

StagedFolder::~StagedFolder() {
  std::error_code ignored;
  if (!committed_) fs::remove_all(staging_, ignored);
}

void StagedFolder::commit() {
  throw_if_stop_requested_before_publishing();
  swap_in();
}

void StagedFolder::swap_in() {
  const fs::path& target = place_;
  if (!fs::exists(target)) {
    fs::rename(staging_, target);
    committed_ = true;
    return;
  }
  if (!fs::is_directory(target)) throw std::runtime_error(target_.string() + ": exists and is not a folder");
  // One step: readers see the old folder or the new one, never a mixture.
  if (::renameat2(AT_FDCWD, staging_.c_str(), AT_FDCWD, target.c_str(), RENAME_EXCHANGE) != 0)
    throw std::runtime_error(target_.string() + ": cannot put the new folder in place: " + std::strerror(errno));
  committed_ = true;
  const fs::path old = staging_;  // now holds the earlier folder
  for (const fs::directory_entry& entry : fs::directory_iterator(old)) {
    const std::string name = entry.path().filename().string();
    if (std::find(owned_.begin(), owned_.end(), name) != owned_.end() || fs::exists(target / name)) continue;
    fs::rename(entry.path(), target / name);
  }
  fs::remove_all(old);
}

}  // namespace ctk
