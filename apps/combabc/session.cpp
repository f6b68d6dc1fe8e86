#include "session.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <memory>
#include <string>

#include "combabc/core/error.hpp"

namespace combabc::cli {

Session::Session([[maybe_unused]] int* argc, [[maybe_unused]] char*** argv) {
#ifdef COMBABC_HAVE_MPI
  if (mpi::MpiSession::LaunchedByMpirun()) {
    mpi_.emplace(argc, argv);
    primary_ = mpi_->rank() == 0;
    executor_ = [](int threads) { return std::make_unique<mpi::MpiExecutor>(threads); };
  }
#endif
  if (!primary_) {
    std::cout.setstate(std::ios::failbit);
    std::cerr.setstate(std::ios::failbit);
  }
}

int Session::Finish(int code) {
  // The other ranks print nothing (their std::cout is failed on purpose).
  if (primary_) code = CheckStandardOutput(code);
#ifdef COMBABC_HAVE_MPI
  if (mpi_) return mpi::ExitCodeOfPrimary(code);
#endif
  return code;
}

int CheckStandardOutput(int code) {
  std::cout.flush();
  errno = 0;
  const bool flushed = std::fflush(stdout) == 0;
  const int error = errno;
  if (flushed && std::ferror(stdout) == 0 && !std::cout.fail()) return code;
  if (code != 0) return code;
  std::cerr << "combabc: I/O error: cannot write to standard output"
            << (error != 0 ? std::string(": ") + std::strerror(error) : std::string()) << "\n";
  return ExitCode(ErrorKind::kIo);
}

}  // namespace combabc::cli
