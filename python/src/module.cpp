// The `ctk._ctk` extension: files, operators, solvers. The package `ctk` (ctk/__init__.py) imports
// it and adds what is Python's own (the scipy adapter, result classes).
#include <pybind11/pybind11.h>

#include <cctype>
#include <string>

#include "bindings.hpp"
#include "ctk/core/error.hpp"
#include "ctk/core/provenance.hpp"

namespace py = pybind11;

PYBIND11_MODULE(_ctk, m) {
  m.doc() = "ctk: calibration and reconstruction of cone-beam CT along arbitrary trajectories";
  // PEP 440: the release, and the commit as a local label ("0.4.0+2b02db5.dirty"), as `ctk --version`
  // names it; __build__ is that line verbatim.
  const std::string build = ctk::build_version();
  std::string commit;
  if (const auto open = build.find('('), close = build.rfind(')'); open != std::string::npos && close > open)
    for (const char c : build.substr(open + 1, close - open - 1)) commit += std::isalnum(static_cast<unsigned char>(c)) ? c : '.';
  m.attr("__version__") = commit.empty() ? std::string(CTK_VERSION) : std::string(CTK_VERSION) + "+" + commit;
  m.attr("__build__") = build;
  // Files written from Python record the script that wrote them.
  std::string invocation = "python";
  // Appended piecewise: `" " + std::string` trips GCC 12's -Wrestrict false positive (GCC PR 105329).
  for (const py::handle& word : py::module_::import("sys").attr("argv"))
    invocation.append(" ").append(py::str(word).cast<std::string>());
  ctk::set_invocation(invocation);

  // InputError: a file the toolkit read is not what it must be; .file and .key say where.
  static py::exception<ctk::InputError> input_error(m, "InputError", PyExc_ValueError);
  // pybind11's translator type takes the pointer by value.
  // NOLINTNEXTLINE(performance-unnecessary-value-param)
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const ctk::InputError& e) {
      py::object type = input_error;
      py::object error = type(e.what());
      error.attr("file") = e.file();
      // where() reads "key 'views[3].P'" for a key; Python gets the key itself.
      const std::string& where = e.where();
      const bool is_key = where.size() > 6 && where.rfind("key '", 0) == 0 && where.back() == '\'';
      error.attr("key") = is_key ? where.substr(5, where.size() - 6) : where;
      PyErr_SetObject(input_error.ptr(), error.ptr());
    }
  });

  ctk::python::bind_files(m);
  ctk::python::bind_operators(m);
  ctk::python::bind_solvers(m);
  ctk::python::bind_measurements(m);
  ctk::python::bind_workflows(m);
  ctk::python::bind_benchmarks(m);
  ctk::python::bind_planning(m);
  ctk::python::bind_phantoms(m);
}
