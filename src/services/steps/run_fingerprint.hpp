#pragma once
// The run's fingerprint (docs/history.md, "Fingerprint"): a 64-bit FNV-1a digest of a canonical
// text of each input that decides the history -- sampler options, parameter space, measured
// data, metric, simulator, combabc version -- and a combined one. Stored with the run; resume
// recomputes it from the problem it rebuilt and refuses to continue a run whose inputs changed,
// since the continuation would no longer equal an uninterrupted run. Private to src/services.
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "combabc/config/config.hpp"
#include "combabc/config/distance_from_config.hpp"
#include "combabc/distances/distance.hpp"
#include "combabc/params/parameter_space.hpp"
#include "combabc/samplers/smc_options.hpp"

namespace combabc::services {

// (part, 16 hex digits), as RunMetadata::fingerprint holds them.
using Fingerprint = std::vector<std::pair<std::string, std::string>>;

struct FingerprintInputs {
  const CalibrationConfig* config = nullptr;  // sampler options, metric, simulator options
  const ParameterSpace* space = nullptr;
  std::span<const MeasuredProfile> data;      // one per experiment, as the metric sees them
  std::vector<DistanceComponent> components;  // the metric as built
  std::string version;                        // combabc version
  std::string handshake;                      // a worker simulator's handshake line, else empty
  std::string low_fidelity_handshake;         // the same for a cheap worker simulator
};

// Parts "sampler", "space", "data", "metric", "simulator", "version", then "combined"; an external
// simulator adds "simulator_outputs" (its declared outputs) and a worker "simulator_handshake"; a
// multi-fidelity run adds "low_fidelity" (its cheap simulator and [sampler.multi_fidelity]).
Fingerprint ComputeFingerprint(const FingerprintInputs& inputs);

// A problem the caller built around a simulator it owns (services::RunProblem: a Python
// function), whose code cannot be fingerprinted: how it is called stands for it.
struct ProblemFingerprintInputs {
  const SmcOptions* options = nullptr;  // as given: its stop limits do not count
  const ParameterSpace* space = nullptr;
  std::span<const double> observed;
  std::span<const double> positions;  // the outputs' coordinates, when given
  std::vector<DistanceComponent> components;
  std::vector<std::pair<std::string, std::string>> calling;  // how the simulator is called
  bool low_fidelity = false;  // a multi-fidelity run (a cheap simulator)
  std::string version;        // combabc version
};

// The same canonical text and parts as ComputeFingerprint: "sampler" (with batch_size, without
// the stop limits), "space", "data", "metric", "python_problem" (the calling), "low_fidelity"
// (multi-fidelity runs: their options), "version", then "combined".
Fingerprint ComputeProblemFingerprint(const ProblemFingerprintInputs& inputs);

// As CheckResumeFingerprint, in a caller's words (kUsage: the caller passed other functions or
// options): "the problem (...) differ" or "the options differ".
void CheckProblemFingerprint(const Fingerprint& stored,
                             const Fingerprint& now,
                             const std::string& history_path,
                             const std::string& stored_version,
                             const std::string& version);

// The same parts with the same digests, in any order (the history stores them sorted).
bool SameFingerprint(Fingerprint a, Fingerprint b);

// How a stored run's config reads when today's reading of it (`now`, its fingerprint) does not
// match the stored fingerprint but an older default does: a sensor run written before RZT became
// the default (combabc before 2026-11-23) has no [model] theory in its config because it was
// Kirchhoff then, and its stored fingerprint says so; it resumes as the run it was (its finished
// waves stay usable). Returns the config as that older reading has it when `fingerprint_of` it
// matches `stored`; nullopt when `now` matches, or no legacy reading does.
std::optional<CalibrationConfig> LegacyReading(
    const CalibrationConfig& config,
    const Fingerprint& now,
    const Fingerprint& stored,
    const std::function<Fingerprint(const CalibrationConfig&)>& fingerprint_of);

// Throws combabc::Error(kConfig), one line naming the history file and what changed, when a part
// stored with the run differs from `now`. A run stored without a fingerprint (schema v1/v2) is
// not checked. data_source names the data file in the message; stored_version the run's combabc;
// handshake, the worker's handshake now (quoted when it is what changed).
void CheckResumeFingerprint(const Fingerprint& stored,
                            const Fingerprint& now,
                            const std::string& history_path,
                            const std::string& data_source,
                            const std::string& stored_version,
                            const std::string& version,
                            const std::string& handshake = {});

}  // namespace combabc::services
