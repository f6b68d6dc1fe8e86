#pragma once
// The simulator a config names, built the same way for a new run, a resume and an enumeration:
// the workflow sees only the Simulator interface and the config's output declaration.
// Private to src/services.
#include <memory>
#include <string>

#include "combabc/config/config.hpp"
#include "combabc/core/thread_pool.hpp"
#include "combabc/samplers/simulator.hpp"

namespace combabc::services {

struct BuiltSimulator {
  // An external simulator's work folder (and the run's `.work` folder it is in), made here when
  // absent and removed, if empty, when the last simulator working in it has gone. Declared
  // before `simulator` so that it outlives it. Null for the sensor.
  std::shared_ptr<const void> folder;
  std::unique_ptr<Simulator> simulator;
  // What identifies the program beyond the config, for the run's fingerprint: a worker's
  // handshake line; empty for the others.
  std::string handshake;
};

// work_directory: where an external simulator makes its per-call / per-worker folders (inside the
// run's output folder). Throws combabc::Error(kConfig) for a simulator that does not fit the
// config (the sensor's clamp count, a worker that fails its handshake). `threads`: lent to the
// sensor's precompute (null: this thread); the sensor uses the precompute cache
// (plate::DefaultPrecomputeCache, docs/model.md).
BuiltSimulator MakeSimulator(const CalibrationConfig& config,
                             const std::string& work_directory,
                             ThreadPool* threads = nullptr);

// A multi-fidelity run's cheap simulator ([simulator.low_fidelity]; none without one), its outputs
// those that stand for the expensive simulator's. An external one works in
// "<work_directory>/low_fidelity" (both folders made here when absent, whatever the expensive
// simulator is).
BuiltSimulator MakeLowFidelitySimulator(const CalibrationConfig& config,
                                        const std::string& work_directory,
                                        ThreadPool* threads = nullptr);

// The work folder of the run whose history is `history_path`: "<history stem>.work" beside it.
std::string WorkDirectoryOf(const std::string& history_path);

}  // namespace combabc::services
