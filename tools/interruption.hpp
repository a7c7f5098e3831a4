#pragma once
// Ctrl-C (SIGINT) or SIGTERM while a long step runs: the first asks that step to stop at its next
// safe point (a solver saves its state there); a second one ends the process at once.
#include <csignal>
#include <stdexcept>

namespace ctk::tools {

class InterruptionWatch {
 public:
  InterruptionWatch() {
    requested_flag() = 0;
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
  static void on_signal(int signal) {
    requested_flag() = 1;
    std::signal(signal, SIG_DFL);  // the second one is not asked politely
  }
  void (*previous_int_)(int);
  void (*previous_term_)(int);
};

/// A run stopped on request, its state saved: exit 130, as a shell reports Ctrl-C.
struct Interrupted : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace ctk::tools
