#pragma once
// Python callables seen from C++ running without the GIL, on any thread: every call takes the GIL
// first; an exception a callable raises, or Ctrl-C (a pending KeyboardInterrupt), is kept and asks
// the run to stop, and is raised in Python once the run has returned.
#include <pybind11/pybind11.h>

#include <functional>
#include <optional>
#include <string>
#include <utility>

#include "interruptible.hpp"

namespace ctk::python {

namespace py = pybind11;

class PythonBridge {
 public:
  /// Runs `f` with the GIL held unless the run is already stopping; keeps what it raises.
  template <class F>
  void with_gil(const F& f) {
    py::gil_scoped_acquire hold;
    if (error_) return;
    try {
      f();
    } catch (py::error_already_set& e) {
      error_.emplace(std::move(e));
    }
  }
  /// `callable(done, total)`, or nothing for None.
  std::function<void(int, int)> progress(py::object callable) {
    return [this, f = std::move(callable)](int done, int total) {
      with_gil([&] {
        if (!f.is_none()) f(done, total);
      });
    };
  }
  /// `callable(line)`, or nothing for None.
  std::function<void(const std::string&)> log(py::object callable) {
    return [this, f = std::move(callable)](const std::string& line) {
      with_gil([&] {
        if (!f.is_none()) f(line);
      });
    };
  }
  /// A callable asked to stop (returned False), raised, or Ctrl-C is pending.
  bool stop_requested() {
    py::gil_scoped_acquire hold;
    if (!error_ && PyErr_CheckSignals() != 0) error_.emplace();
    return stopped_ || error_.has_value();
  }
  void request_stop() { stopped_ = true; }
  bool stopped_by_request() const { return stopped_ && !error_; }
  /// Raises what a callable or Ctrl-C raised, if anything.
  void raise_if_stopped() {
    if (error_) throw std::move(*error_);
  }
  /// Called by a run's hook (a log line, a progress step) of a run that has no stop request of
  /// its own: ends the run there, by an exception run_stoppable() catches, when it is stopping.
  void end_run_if_stopping() {
    if (stop_requested()) throw Stopping{};
  }
  /// Runs `work` as interruptible() does, ended early by end_run_if_stopping(), then raises what a
  /// callable or Ctrl-C raised; returns without raising when a callable asked the run to stop.
  template <class Work>
  void run_stoppable(Work&& work) {
    try {
      interruptible(std::forward<Work>(work));
    } catch (const Stopping&) {
    }
    raise_if_stopped();
  }

 private:
  struct Stopping {};
  bool stopped_ = false;
  std::optional<py::error_already_set> error_;
};

}  // namespace ctk::python
