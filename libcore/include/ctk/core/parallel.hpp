#pragma once
// OpenMP loops whose body may throw: an exception escaping an OpenMP region ends the program,
// so the first one is kept, the remaining iterations are skipped, and it is rethrown after. A stop
// requested from outside (cancellation.hpp) skips the remaining iterations too, and throws Cancelled.
#include <atomic>
#include <exception>
#include <mutex>

#include "ctk/core/cancellation.hpp"

namespace ctk {

template <typename Body>
void parallel_for_dynamic(int count, Body&& body) {
  std::exception_ptr error;
  std::mutex error_mutex;
  std::atomic<bool> failed{false};
#pragma omp parallel for schedule(dynamic)
  for (int i = 0; i < count; ++i) {
    if (failed.load(std::memory_order_relaxed) || stop_requested()) continue;
    try {
      body(i);
    } catch (...) {
      const std::lock_guard<std::mutex> lock(error_mutex);
      if (!error) error = std::current_exception();
      failed = true;
    }
  }
  if (error) std::rethrow_exception(error);
  throw_if_stop_requested();
}

}  // namespace ctk
