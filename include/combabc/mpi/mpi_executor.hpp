#pragma once
// MPI (issue 10): every rank runs the whole program (SPMD) with the same inputs; MpiExecutor gives
// each rank a contiguous slice of every batch, evaluates it on the rank's own threads and gathers
// every result buffer's rows onto all ranks (MPI_Allgatherv), so that all ranks hold the same state
// and take the same decisions. Which rank simulated a candidate never changes its result (its
// randomness is RandomStream(seed, wave, index)), hence the same history for any number of ranks
// and threads. Rank 0 is the primary: it alone writes files and prints (docs/architecture.md).
// This header does not include <mpi.h>: only this layer is built against MPI.
#include <exception>

#include "combabc/core/executor.hpp"

namespace combabc::mpi {

// MPI_Init_thread (funneled: only the main thread calls MPI) on construction, MPI_Finalize on
// destruction; one per process, in main().
class MpiSession {
 public:
  MpiSession(int* argc, char*** argv);
  ~MpiSession();
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }
  // True when this process was started by mpirun/mpiexec (OpenMPI, MPICH, PMIx launchers): a
  // plain `combabc run` never initialises MPI.
  static bool LaunchedByMpirun();

 private:
  int rank_ = 0;
  int size_ = 1;
};

class MpiExecutor : public Executor {
 public:
  // Needs an MpiSession; threads per rank as for ThreadPoolExecutor (0: all cores, 1: inline).
  explicit MpiExecutor(int threads);
  int concurrency() const override { return local_.concurrency() * size_; }
  // Throws on every rank, with the same message, when any rank's slice threw; an MPI failure
  // (a rank that died) is Error(kSoftware) naming MPI.
  void Execute(std::size_t n, BatchTask& task) override;
  bool primary() const override { return rank_ == 0; }
  void Join(const std::exception_ptr& error) override;
  bool FromPrimary(bool value) override;
  double FromPrimary(double value) override;

  int rank() const { return rank_; }
  int size() const { return size_; }

 private:
  ThreadPoolExecutor local_;
  int rank_ = 0;
  int size_ = 1;
};

// Rank 0's exit code on every rank (the CLI's last collective), so that mpirun and every rank
// agree.
int ExitCodeOfPrimary(int code);

}  // namespace combabc::mpi
