#pragma once
// Adding experiments to a finished run (docs/algorithm.md, "Adding data to a finished run";
// `combabc run CONFIG --from RUN.sqlite`): the finished run's posterior as the population a new
// run of `p` starts from. Private to src/services.
#include <string>
#include <utility>
#include <vector>

#include "combabc/samplers/combinatorial_smc.hpp"
#include "services/steps/problem.hpp"

namespace combabc::services {

// The last complete wave of the run in `history_path` as p's start: its parameters and weights,
// the thresholds of the components it had (by name) and infinity for the new ones. Throws
// Error(kConfig) naming `history_path` when the run cannot be continued this way: other bits or
// reals, a component or experiment of the finished run missing from p or with other data, no
// new experiment, no complete wave.
StartPopulation StartFromFinishedRun(const std::string& history_path, const Problem& p);

// A caller-built problem's start (services::RunProblem, start_from=): the same bits and reals by
// name, any data and distance; the finished run's components keep their final thresholds by name.
// Its simulator may be stochastic: wave 0 does not compare the distances again.
StartPopulation StartFromFinishedRun(const std::string& history_path,
                                     const ParameterSpace& space,
                                     const std::vector<DistanceComponent>& components);

// The fingerprint part that records which run a run started from: ("start", that run's combined
// fingerprint). A resume keeps it (the start population is the run's wave 0 by then).
std::pair<std::string, std::string> StartFingerprint(const std::string& history_path);

}  // namespace combabc::services
