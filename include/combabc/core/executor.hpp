#pragma once
// Where a batch of candidates is evaluated: the seam between the sampler and the machines. The
// sampler hands an executor a BatchTask over candidate indices [0, n); the executor makes sure
// EvaluateRange has run over every index and that every result buffer holds every candidate's
// results when Execute returns. A shared-memory executor (ThreadPoolExecutor) just runs the
// ranges on its threads; an executor whose workers do not share memory (MPI, issue 10) runs a
// slice per worker and then gathers the slices of each result buffer.
#include <cstddef>
#include <exception>
#include <span>
#include <vector>

#include "combabc/core/thread_pool.hpp"

namespace combabc {

class BatchTask {
 public:
  virtual ~BatchTask() = default;
  // Evaluates candidates [begin, end): writes only their rows of the result buffers.
  virtual void EvaluateRange(std::size_t begin, std::size_t end) = 0;
  // The per-candidate results, each a row-major array of `row_bytes` per candidate; rows of one
  // candidate are what a distributed executor gathers.
  struct Buffer {
    void* data = nullptr;
    std::size_t row_bytes = 0;
  };
  virtual std::vector<Buffer> Results() = 0;
};

class Executor {
 public:
  virtual ~Executor() = default;
  // Number of candidates worth evaluating at once (threads x ranks), for batch sizing.
  virtual int concurrency() const = 0;
  // Runs task over [0, n); rethrows the first exception a range threw (on every worker).
  virtual void Execute(std::size_t n, BatchTask& task) = 0;

  // A distributed executor runs one copy of the whole program per worker (SPMD: same inputs, same
  // seed, hence the same proposals and decisions everywhere). These three keep the copies in step;
  // a shared-memory executor has one worker and they are trivial.
  //
  // The worker that writes files and prints progress.
  virtual bool primary() const { return true; }
  // Every worker calls it at the same point with its own outcome of a step (null: it succeeded);
  // returns on all when none failed, else throws on all the failure of the first that failed
  // (combabc::Error keeps its kind), so that a step only the primary does (creating the history)
  // cannot leave the others running, and every worker exits with the same code.
  virtual void Join(const std::exception_ptr& error) {
    if (error) std::rethrow_exception(error);
  }
  // The primary's value, on every worker: for decisions that are not a function of the inputs
  // (the wall clock, an interruption) and must nevertheless be the same everywhere.
  virtual bool FromPrimary(bool value) { return value; }
  // The same for a number (the measured cost of a simulation, which sizes the batches).
  virtual double FromPrimary(double value) { return value; }
  // This worker's threads, for work that is not a batch of candidates (a simulator's set-up: the
  // sensor's precompute); null when it has none to lend.
  virtual ThreadPool* thread_pool() { return nullptr; }
};

// Shared memory: ranges run on a ThreadPool (threads = 0: all cores; 1: inline, no threads).
class ThreadPoolExecutor : public Executor {
 public:
  explicit ThreadPoolExecutor(int threads) : pool_(threads) {}
  int concurrency() const override { return pool_.size(); }
  void Execute(std::size_t n, BatchTask& task) override;
  ThreadPool* thread_pool() override { return &pool_; }

 private:
  ThreadPool pool_;
};

}  // namespace combabc
