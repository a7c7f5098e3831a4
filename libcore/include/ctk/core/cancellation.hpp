#pragma once
// A run asked to stop from outside while it computes (Ctrl-C in Python, where the interpreter's
// thread waits for the computing one): the long parallel loops look at the request between their
// pieces of work, skip the rest, and throw Cancelled when they end, so a projection of seconds
// stops within a fraction of one. Nothing asks for it unless a caller does; the command line's own
// Ctrl-C keeps its meaning (finish the iteration, keep the state).
#include <atomic>
#include <functional>
#include <stdexcept>
#include <utility>

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

namespace detail {
inline std::function<void()>& publish_check() {
  thread_local std::function<void()> check;
  return check;
}
}  // namespace detail

/// While one lives, `look` runs on this thread just before its outputs are published: a front end
/// whose stop requests arrive late (Python sees Ctrl-C only in its main thread, up to a poll's
/// period after the signal) looks for one there, the last moment a stop can still leave nothing.
class PublishCheck {
 public:
  explicit PublishCheck(std::function<void()> look) { detail::publish_check() = std::move(look); }
  ~PublishCheck() { detail::publish_check() = nullptr; }
  PublishCheck(const PublishCheck&) = delete;
  PublishCheck& operator=(const PublishCheck&) = delete;
};

/// Called by whatever makes a run's outputs visible (output_set.hpp): a run stopped before this
/// point publishes nothing.
inline void throw_if_stop_requested_before_publishing() {
  if (const std::function<void()>& look = detail::publish_check()) look();
  throw_if_stop_requested();
}

}  // namespace ctk
