#pragma once
// A run asked to stop from outside while it computes (Ctrl-C in Python, where the interpreter's
// thread waits for the computing one): the long parallel loops look at the request between their
// pieces of work, skip the rest, and throw Cancelled when they end, so a projection of seconds
// stops within a fraction of one. Nothing asks for it unless a caller does; the command line's own
// Ctrl-C keeps its meaning (finish the iteration, keep the state).
#include <atomic>
#include <stdexcept>

namespace ctk {

class Cancelled : public std::runtime_error {
 public:
  Cancelled() : std::runtime_error("stopped on request") {}
};

namespace detail {
// Lock-free, so that a signal handler may request a stop (tools/interruption.hpp).
static_assert(std::atomic<bool>::is_always_lock_free);
inline std::atomic<bool>& stop_flag() {
  static std::atomic<bool> flag{false};
  return flag;
}
}  // namespace detail

inline bool stop_requested() noexcept { return detail::stop_flag().load(std::memory_order_relaxed); }
inline void request_stop() noexcept { detail::stop_flag().store(true); }
inline void clear_stop_request() noexcept { detail::stop_flag().store(false); }
inline void throw_if_stop_requested() {
  if (stop_requested()) throw Cancelled();
}

}  // namespace ctk
