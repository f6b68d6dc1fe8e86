#pragma once
// What the files of combabc._core share (module.cpp registers them): the enum parser, the options
// checks, the history read back as a dict, and one helper for the pattern every job follows (the
// GIL released while C++ works, Ctrl-C polled between batches and raised after).
#include <pybind11/pybind11.h>

#include <functional>
#include <optional>
#include <string>

#include "combabc/core/enum_names.hpp"
#include "combabc/core/error.hpp"
#include "combabc/history/history_store.hpp"
#include "combabc/samplers/observer.hpp"
#include "combabc/samplers/smc_options.hpp"
#include "history_arrays.hpp"

namespace combabc::python {

// A config's choice by its name: Error(kConfig) naming `field` and the choices.
template <NamedEnum E>
E Parse(const std::string& text, const std::string& field) {
  const std::optional<E> value = ParseEnum<E>(text);
  if (!value) {
    throw Error(ErrorKind::kConfig,
                "unknown value " + Excerpt(text) + "; expected one of " + EnumChoices<E>(),
                {},
                0,
                field);
  }
  return *value;
}

// Ctrl-C from Python: polled between batches on the thread that called the run (the Python thread
// that started it, where Python runs its signal handlers), it runs them and stops the run when one
// raised (KeyboardInterrupt). The run ends as interrupted (a config run stays resumable) and the
// caller raises the error again.
class PythonSignals final : public SmcObserver {
 public:
  bool ShouldStop() override;
  // Raises the exception a signal handler raised, if any (GIL held), with `note` attached.
  void RaiseIfInterrupted(const std::string& note);

 private:
  std::optional<pybind11::error_already_set> raised_;
};

// A job (a service call taking the observer that polls Ctrl-C) run with the GIL released; then,
// GIL held, `on_error` sees what it threw (to raise a user's Python exception as itself) before
// it is rethrown, and an interrupt is raised with the note `interrupted` gives for the outcome.
template <typename Outcome>
Outcome RunReleased(const std::function<Outcome(SmcObserver*)>& job,
                    const std::function<std::string(const Outcome&)>& interrupted,
                    const std::function<void(const std::exception&)>& on_error = {}) {
  PythonSignals signals;
  Outcome outcome;
  try {
    const pybind11::gil_scoped_release release;
    outcome = job(&signals);
  } catch (const std::exception& e) {
    if (on_error) on_error(e);
    throw;
  }
  signals.RaiseIfInterrupted(interrupted(outcome));
  return outcome;
}

// The note of an interrupted run that wrote `path`: how to continue it.
std::string ContinueNote(const std::string& path, const std::string& arguments = "");

// A history file as the pure-Python History reads it (combabc.load_history), with
// report_directory when not empty.
pybind11::dict LoadHistory(const std::string& path, const std::string& report_directory = "");

// The export's names for the columns of a run's arrays.
HistoryNames NamesOf(const RunMetadata& metadata, const RunHistory& history);

// Each continuous parameter's prior as summary.json's "reals" give it (History.real_priors).
pybind11::list RealPriors(const std::vector<ContinuousParameter>& reals);

// MultiFidelityOptions and MoveOptions as their keywords name them: ValueError naming the
// argument.
void CheckMultiFidelity(const MultiFidelityOptions& o);
void CheckMoves(const MoveOptions& o);

// What each file binds.
void BindTypes(pybind11::module_& m);          // bind_types.cpp: spaces, parameters, options
void BindProposalTypes(pybind11::module_& m);  // bind_proposals.cpp: kernels and tempering
void BindJobs(pybind11::module_& m);           // bind_jobs.cpp: config runs, export, simulate
void BindProblemRuns(pybind11::module_& m);    // bind_problem_runs.cpp: Python problems

}  // namespace combabc::python
