#pragma once
// Ctrl-C (SIGINT) or SIGTERM while a long step runs: the first asks that step to stop at its next
// safe point (a solver saves its state there); a second one ends the process at once. A command
// whose work has no state worth keeping (simulate) has the library's parallel loops stop as well
// (cancellation.hpp): they skip what is left and end with Cancelled.
#include <csignal>
#include <stdexcept>
#include <string>

#include "ctk/core/cancellation.hpp"

namespace ctk::tools {

class InterruptionWatch {
 public:
  enum class Stop { at_the_next_safe_point, the_parallel_loops_too };
  explicit InterruptionWatch(Stop stop = Stop::at_the_next_safe_point) {
    requested_flag() = 0;
    stops_loops_flag() = stop == Stop::the_parallel_loops_too ? 1 : 0;
    previous_int_ = std::signal(SIGINT, on_signal);
    previous_term_ = std::signal(SIGTERM, on_signal);
  }
  ~InterruptionWatch() {
    std::signal(SIGINT, previous_int_);
    std::signal(SIGTERM, previous_term_);
  }
  InterruptionWatch(const InterruptionWatch&) = delete;
  InterruptionWatch& operator=(const InterruptionWatch&) = delete;

  static bool requested() { return requested_flag() != 0; }

 private:
  static volatile std::sig_atomic_t& requested_flag() {
    static volatile std::sig_atomic_t flag = 0;
    return flag;
  }
  static volatile std::sig_atomic_t& stops_loops_flag() {
    static volatile std::sig_atomic_t flag = 0;
    return flag;
  }
  static void on_signal(int signal) {
    requested_flag() = 1;
    if (stops_loops_flag()) request_stop();  // a lock-free atomic store: safe in a handler
    std::signal(signal, SIG_DFL);            // the second one is not asked politely
  }
  void (*previous_int_)(int);
  void (*previous_term_)(int);
};

/// A run stopped on request, its state saved: exit 130, as a shell reports Ctrl-C.
struct Interrupted : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Runs `work`, a command's computation before it writes anything, so that Ctrl-C or SIGTERM ends
/// the command with exit 130 and nothing written: the library's parallel loops stop at once, and
/// a signal that came during a step without such loops (a solve) is honoured when `work` returns.
template <class Work>
auto stoppable(const std::string& stopped, Work&& work) {
  const InterruptionWatch watch(InterruptionWatch::Stop::the_parallel_loops_too);
  try {
    auto result = work();
    if (InterruptionWatch::requested()) throw Cancelled();
    return result;
  } catch (const Cancelled&) {
    throw Interrupted(stopped);
  }
}

}  // namespace ctk::tools
