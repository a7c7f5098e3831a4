#pragma once
// Long computations that Ctrl-C stops within a fraction of a second. Python runs signal handlers
// only in its main thread, and only between bytecodes: so the work runs on a thread of its own
// (GIL released) while the calling thread looks for a KeyboardInterrupt every 20 ms. On one it asks
// the work to stop (cancellation.hpp: the projector's and the parallel loops' pieces end early),
// waits for it, and raises the KeyboardInterrupt. Callbacks of the work (progress, a solver's
// per-iteration callable) take the GIL as before. Before the work publishes its outputs it asks the
// calling thread to look once more (PublishCheck), so a Ctrl-C that came before that point, even
// within the last poll's period, leaves nothing written.
#include <pybind11/pybind11.h>

#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <optional>
#include <thread>
#include <type_traits>
#include <utility>

#include "ctk/core/cancellation.hpp"

namespace ctk::python {

namespace py = pybind11;

/// Call with the GIL held. Returns what `work` returns; rethrows what it throws.
template <class Work>
auto interruptible(Work&& work) -> decltype(work()) {
  using Result = decltype(work());
  std::mutex mutex;
  std::condition_variable finished;
  bool done = false;
  bool look_asked = false, looked = false;  // the worker's question before publishing, and its answer
  std::exception_ptr error;
  std::conditional_t<std::is_void_v<Result>, int, std::optional<Result>> result{};
  clear_stop_request();
  std::thread worker([&] {
    const PublishCheck look([&] {
      std::unique_lock lock(mutex);
      look_asked = true;
      looked = false;
      finished.notify_all();
      finished.wait(lock, [&] { return looked; });
    });
    try {
      if constexpr (std::is_void_v<Result>)
        work();
      else
        result.emplace(work());
    } catch (...) {
      error = std::current_exception();
    }
    const std::lock_guard lock(mutex);
    done = true;
    finished.notify_all();
  });
  bool interrupted = false;
  while (true) {
    bool answer = false;
    {
      py::gil_scoped_release free;
      std::unique_lock lock(mutex);
      if (finished.wait_for(lock, std::chrono::milliseconds(20), [&] { return done || look_asked; }) && done) break;
      answer = look_asked;
    }
    if (!interrupted && PyErr_CheckSignals() != 0) {  // sets the KeyboardInterrupt
      interrupted = true;
      request_stop();
    }
    if (answer) {
      const std::lock_guard lock(mutex);
      look_asked = false;
      looked = true;
      finished.notify_all();
    }
  }
  {
    py::gil_scoped_release free;
    worker.join();
  }
  clear_stop_request();
  if (interrupted) throw py::error_already_set();
  if (error) std::rethrow_exception(error);
  if constexpr (!std::is_void_v<Result>) return std::move(*result);
}

}  // namespace ctk::python
