#pragma once
// Combinatorial ABC-SMC (paper section 3) and ABC rejection (paper Algorithm 1).
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "combabc/core/executor.hpp"
#include "combabc/distances/distance.hpp"
#include "combabc/params/parameter_space.hpp"
#include "combabc/proposals/proposal.hpp"
#include "combabc/samplers/observer.hpp"
#include "combabc/samplers/run_history.hpp"
#include "combabc/samplers/simulator.hpp"
#include "combabc/samplers/smc_options.hpp"

namespace combabc {

// Where to continue a run: its completed waves and, optionally, the particles the last
// (incomplete) wave had accepted before candidate index next_index. Because every candidate's
// randomness is a function of (seed, wave, index), continuing from here gives the same history as
// an uninterrupted run.
struct ResumePoint {
  std::vector<WaveRecord> completed;
  bool has_partial = false;
  int partial_wave = 0;
  std::int64_t partial_next_index = 0;
  std::vector<Particle> partial_accepted;
  std::int64_t partial_discarded = 0;               // BatchProgress::discarded of the partial wave
  std::vector<SimulationFailure> partial_failures;  // its failed simulations below next_index
  // Its continuation probabilities and costs so far (multi-fidelity runs): a resumed wave goes on
  // with the probabilities it started with.
  std::optional<WaveFidelity> partial_fidelity;
};

// A finished run's posterior that a new run starts from instead of the prior, to add data to it
// (IBIS, Chopin 2002; docs/algorithm.md, "Adding data to a finished run"): wave 0 re-simulates
// these parameters under the new problem (the old experiments and the new ones) and keeps them
// with their weights, at the finished run's final thresholds for the components it had and
// infinite ones for the new; the waves after it bring the new components to their targets.
struct StartPopulation {
  std::vector<ParameterValue> thetas;
  std::vector<double> weights;     // one per theta, >= 0, not all 0
  std::vector<double> thresholds;  // one per schedule slot of the new distance
  // Optional, for a deterministic simulator: per theta, the finished run's distance for each
  // component of the new distance (NaN for a new component). A re-simulated distance that
  // differs (beyond 1e-9 relative) throws Error(kConfig): the model or the old data changed, and
  // the population is no longer a draw from the old posterior.
  std::vector<std::vector<double>> expected;
};

// What a run infers and with what. The sampler knows kernels, executors and simulators only
// through these interfaces.
struct SmcProblem {
  const ParameterSpace* space = nullptr;
  const Simulator* simulator = nullptr;
  const Distance* distance = nullptr;
  // Optional. Null: made from SmcOptions::proposal (MakeJointKernel) and a ThreadPoolExecutor of
  // SmcOptions::threads.
  const JointKernel* kernel = nullptr;
  Executor* executor = nullptr;
  // Optional: a cheap simulator with the same outputs as `simulator`. Set, every candidate runs
  // it and the expensive `simulator` runs only with SmcOptions::multi_fidelity's continuation
  // probabilities (docs/algorithm.md, "Multi-fidelity sampling").
  const Simulator* low_fidelity = nullptr;
  // Optional: the population wave 0 starts from (above); null = the prior.
  const StartPopulation* start = nullptr;
};

// Runs waves t = 0..num_waves-1: wave 0 proposes from the prior, wave t+1 from the kernels fitted
// to wave t's weighted particles (for the independent kernel: the tempered per-bit marginals of
// Eqs. 2-3). A failed simulation (SimulationFailed, NaN output or distance) is a rejected
// candidate recorded in WaveRecord::failures. Throws combabc::Error for invalid options (kConfig)
// or any other simulator/distance exception (kSoftware, naming wave and candidate).
RunHistory RunCombinatorialSmc(const SmcProblem& problem,
                               const SmcOptions& options,
                               SmcObserver* observer = nullptr,
                               const ResumePoint* resume = nullptr);

// The stop (budget, failure ceiling or acceptance floor) that a run continued from `resume` under
// `options` would make before simulating anything more, if any: what a resume of a stopped run
// checks before it rewrites the history (services::ResumeCalibration).
std::optional<std::pair<Termination, std::string>> ImmediateStop(const SmcOptions& options,
                                                                 const ResumePoint& resume);

// ABC rejection (Algorithm 1): propose from the prior until n accepted with the given thresholds
// (one per threshold component). One wave of the same machinery.
RunHistory RunRejection(const SmcProblem& problem,
                        int accepted,
                        const std::vector<double>& thresholds,
                        std::uint64_t seed,
                        int threads = 1,
                        std::int64_t max_simulations = 0);

}  // namespace combabc
