// combabc._core: the compiled half of the Python module (docs/python.md). It binds the options and
// parameter types, runs config files through the same services as the CLI, runs problems whose
// simulator is written in Python, and reads histories as NumPy arrays. The pure-Python package
// (python/combabc/) wraps it in DataFrames. The GIL is released while C++ works.
//
// This file registers what the others bind, one line each (bindings.hpp):
//   bind_types.cpp, bind_proposals.cpp  the parameter and options types
//   python_prior.cpp                    custom and joint priors
//   bind_jobs.cpp                       config runs, resume, enumerate, export, the simulator
//   bind_problem_runs.cpp               runs of problems written in Python
//   answer_binding.cpp                  the answer (History.answer())
//   python_model_choice.cpp             model choice (docs/algorithm.md, "Model choice")
#include <pybind11/pybind11.h>

#include <exception>
#include <string>

#include "answer_binding.hpp"
#include "bindings.hpp"
#include "combabc/core/error.hpp"
#include "combabc/params/binary_space.hpp"
#include "combabc/samplers/simulator.hpp"
#include "python_model_choice.hpp"
#include "python_prior.hpp"

namespace py = pybind11;

PYBIND11_MODULE(_core, m) {
  using namespace combabc;
  using namespace combabc::python;
  m.doc() = "combabc's compiled core; use the combabc package (docs/python.md)";
  m.attr("__version__") = COMBABC_PYTHON_VERSION;
  // The most bits a BinarySpace (or a config's [simulator.bits]) may declare.
  m.attr("MAX_BITS") = kMaxBits;

  // combabc::Error as combabc.Error, its message as the CLI prints it after "combabc: ".
  static py::exception<Error> error_type(m, "Error", PyExc_RuntimeError);
  // By value: pybind11's ExceptionTranslator is void (*)(std::exception_ptr).
  // NOLINTNEXTLINE(performance-unnecessary-value-param)
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Error& e) {
      const auto type = py::reinterpret_borrow<py::object>(error_type.ptr());
      py::object exception = type(std::string(ToString(e.kind())) + ": " + std::string(e.what()));
      exception.attr("kind") = std::string(ToString(e.kind()));
      exception.attr("exit_code") = ExitCode(e.kind());
      PyErr_SetObject(error_type.ptr(), exception.ptr());
    }
  });
  static py::exception<SimulationFailed> failed_type(m, "SimulationFailed", PyExc_RuntimeError);
  static_cast<void>(failed_type);

  BindTypes(m);
  BindAnswer(m);  // answer(path): History.answer()
  RegisterPriors(m);
  RegisterModelChoice(m);
  BindJobs(m);
  BindProblemRuns(m);
}
