#pragma once
// A service's steps under an executor that may be distributed (MPI: every worker runs the same
// service): done on the primary only or on every worker, then joined, so that one worker's
// failure is thrown on all and every worker returns or throws alike. Private to src/services.
#include <exception>

#include "combabc/core/executor.hpp"

namespace combabc::services {

// Runs `step` on the primary only, then joins: its failure is thrown on every worker.
template <typename Step>
void OnPrimary(Executor& executor, Step&& step) {
  std::exception_ptr error;
  if (executor.primary()) {
    try {
      step();
    } catch (...) {
      error = std::current_exception();
    }
  }
  executor.Join(error);
}

// Runs `step` on every worker, then joins: one worker's failure is thrown on all.
template <typename Step>
void OnEvery(Executor& executor, Step&& step) {
  std::exception_ptr error;
  try {
    step();
  } catch (...) {
    error = std::current_exception();
  }
  executor.Join(error);
}

}  // namespace combabc::services
