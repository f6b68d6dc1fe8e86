#pragma once
// A run history as plain Python objects: a dict per wave holding NumPy arrays (particles, weights,
// distances, marginals), which the pure-Python layer (combabc/history.py) turns into DataFrames.
#include <pybind11/pybind11.h>

#include <string>
#include <vector>

#include "combabc/history/history_store.hpp"
#include "combabc/samplers/run_history.hpp"

namespace combabc::python {

// What the arrays' columns are called: the export's names (docs/history.md, "Export").
struct HistoryNames {
  std::vector<std::string> bits;        // one per bit
  std::vector<std::string> reals;       // one per continuous parameter
  std::vector<std::string> components;  // one per distance component
  // The export's column names (ThresholdColumns, DistanceColumns in export/export.hpp).
  std::vector<std::string> threshold_columns;
  std::vector<std::string> distance_columns;
  std::string estimator;  // "paper" or "importance"
  // The kernels the run used, `auto` resolved (summary.json's "proposal").
  std::string binary_kernel;
  std::string continuous_kernel;
  // An enumeration's numbers are exact: no Monte-Carlo errors. bit_prior_one: a bit its prior
  // fixes has no error either (WaveMonteCarloErrors).
  bool exact = false;
  std::vector<double> bit_prior_one;
};

// Keys: "names" (bits, reals, components, threshold_columns, distance_columns), "estimator",
// "proposal" (binary_kernel, continuous_kernel),
// "summary" (termination, message, waves completed, simulations, discarded, failures, wall seconds)
// and "waves", a list of dicts, one per wave: its statistics (wave is 0-based), its Monte-Carlo
// errors as summary.json's "waves" entries name them (marginals_se, marginals_ess, ess_bits,
// reals_mean_se, reals_sd_se, reals_ess: samplers/monte_carlo_error.hpp; NaN when exact), then
// the particles'
// index int64[n], bits uint8[n, d], reals float64[n, r], log_weight and weight float64[n], distance
// float64[n, k], output float64[n, m] (m = 0 without kept outputs), failure_index /
// failure_reason, and for a multi-fidelity wave "multi_fidelity" (a dict of WaveFidelity's
// fields) and the particles' multiplier float64[n], confirmed bool[n] and low_distance
// float64[n, k] (None each in a single-fidelity run).
pybind11::dict HistoryToDict(const RunHistory& history, const HistoryNames& names);

// The run's experiments (ExperimentSlices in export/export.hpp: one unnamed experiment holding
// everything for a file older than schema v6), a dict each: name, description, and the start
// and size of its slices of the outputs, measured points and distance components
// (first_output, outputs, first_measured, measured, first_component, components).
pybind11::list ExperimentsToList(const RunMetadata& metadata);

}  // namespace combabc::python
