#pragma once
// A progress line for long runs: done / total, elapsed time and an estimate of the time left,
// rewritten in place on a terminal, printed at every 10 % otherwise.
#include <unistd.h>
#include <chrono>
#include <cstdio>
#include <string>

namespace ctk::tools {

class Progress {
 public:
  Progress(std::string what, std::string unit) : what_(std::move(what)), unit_(std::move(unit)) {}

  void operator()(int done, int total) {
    if (silenced()) return;
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    const int decile = total > 0 ? 10 * done / total : 10;
    const bool tty = isatty(fileno(stderr));
    if (!tty && decile == last_decile_ && done != total) return;
    last_decile_ = decile;
    const double left = done > 0 ? elapsed * (total - done) / done : 0.0;
    std::fprintf(stderr, "%s%s: %d / %d %s, %.1f s elapsed, ~%.1f s left%s", tty ? "\r" : "", what_.c_str(), done, total,
                 unit_.c_str(), elapsed, left, tty && done != total ? "" : "\n");
    std::fflush(stderr);
  }

  /// Every progress line of the process off (the ranks of a run other than the first).
  static bool& silenced() {
    static bool off = false;
    return off;
  }

 private:
  std::string what_, unit_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  int last_decile_ = -1;
};

}  // namespace ctk::tools
