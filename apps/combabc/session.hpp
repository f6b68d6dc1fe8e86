#pragma once
// How this process takes part in the command: alone, or as one rank of an mpirun job.
#include <optional>

#include "combabc/services/executor_factory.hpp"
#ifdef COMBABC_HAVE_MPI
#include "combabc/mpi/mpi_executor.hpp"
#endif

namespace combabc::cli {

// Under mpirun (and only there: a plain run never touches MPI) every rank runs the same command
// (SPMD, docs/architecture.md): run, resume and enumerate spread their simulations over the
// ranks; rank 0 alone prints and writes files, the others are silent; all exit with rank 0's
// code.
class Session {
 public:
  // After the command line is parsed: MPI_Init may change argc and argv.
  Session(int* argc, char*** argv);
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  // The rank that prints and writes files: the only one without mpirun.
  bool primary() const { return primary_; }
  // The services' executor: MPI ranks under mpirun, else empty (threads on this machine).
  const services::ExecutorFactory& executor() const { return executor_; }
  bool under_mpirun() const { return static_cast<bool>(executor_); }

  // The process's exit code once the command returned `code`: on rank 0, 74 if what it printed
  // did not reach standard output (CheckStandardOutput); under mpirun, rank 0's code on every
  // rank.
  int Finish(int code);

 private:
  bool primary_ = true;
  services::ExecutorFactory executor_;
#ifdef COMBABC_HAVE_MPI
  std::optional<mpi::MpiSession> mpi_;
#endif
};

// What was printed reached standard output, or (a full disk, /dev/full, a closed pipe's reader
// gone) exit 74 saying so: `combabc verify RUN > report.txt` on a full disk must not exit 0.
// `code` is the command's own exit code; an earlier failure keeps its code and its message.
int CheckStandardOutput(int code);

}  // namespace combabc::cli
