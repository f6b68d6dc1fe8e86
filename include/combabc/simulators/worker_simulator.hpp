#pragma once
// Long-lived worker processes speaking the line protocol "combabc-worker 2" on stdin/stdout
// (docs/simulators.md, "Worker protocol"): a handshake line, then one request line and one
// answer line per candidate, both carrying the request's id. One worker per executor slot: a call
// takes an idle worker (or starts one), so no more run than threads call Simulate at once. A
// worker that crashes, times out or breaks the protocol (an answer with another id, more than one
// line per request) is killed with its process group; the candidate is retried on a new worker
// `retries` times, then throws SimulationFailed. Thread-safe.
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <vector>

#include "combabc/samplers/simulator.hpp"
#include "combabc/simulators/external_simulator.hpp"
#include "combabc/simulators/work_directory.hpp"

namespace combabc {

inline constexpr const char* kWorkerProtocol = "combabc-worker";
inline constexpr int kWorkerProtocolVersion = 2;

class WorkerSimulator : public Simulator {
 public:
  // Starts one worker and checks its handshake: throws combabc::Error(kConfig) naming what is
  // wrong (invalid options, a program that cannot start, a wrong protocol, version or output
  // size).
  explicit WorkerSimulator(ExternalSimulatorOptions options);
  ~WorkerSimulator() override;
  int output_size() const override { return options_.output_size; }
  void Simulate(const ParameterView& theta,
                RandomStream& rng,
                std::span<double> out) const override;
  // The first worker's handshake line, verbatim: part of the simulator's identity (its free text
  // after the output size names the model and its version).
  const std::string& handshake() const { return handshake_; }

  class Worker;

 private:
  // A new worker past its handshake, or nullptr with *reason. first_handshake: where to store
  // the handshake of the first worker (the constructor's); later ones must match it.
  std::unique_ptr<Worker> Start(std::string* reason, std::string* first_handshake) const;
  std::string Attempt(Worker& worker,
                      const ParameterView& theta,
                      std::span<double> out,
                      bool* in_step) const;

  ExternalSimulatorOptions options_;
  WorkDirectory work_;
  std::string handshake_;
  mutable std::mutex mutex_;
  mutable std::vector<std::unique_ptr<Worker>> idle_;
};

}  // namespace combabc
