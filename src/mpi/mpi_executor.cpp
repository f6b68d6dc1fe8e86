#include "combabc/mpi/mpi_executor.hpp"

#include <mpi.h>

#include <climits>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

#include "combabc/core/error.hpp"

namespace combabc::mpi {
namespace {

// Every MPI call is checked: with MPI_ERRORS_RETURN a rank that died makes the next collective
// fail here (where the transport notices) instead of aborting without a word.
void Check(int code, const char* call) {
  if (code == MPI_SUCCESS) return;
  char text[MPI_MAX_ERROR_STRING] = {};
  int length = 0;
  MPI_Error_string(code, text, &length);
  throw Error(ErrorKind::kSoftware,
              std::string("MPI: ") + call + " failed (" + std::string(text, length) +
                  "): a rank died or the connection between ranks failed; the finished waves "
                  "are kept in the history ('combabc resume' continues the run)");
}

// [begin, end) of rank r's slice of [0, n): contiguous, sizes differing by at most one.
std::size_t SliceBegin(std::size_t n, int r, int size) {
  return n * static_cast<std::size_t>(r) / static_cast<std::size_t>(size);
}

// The local slice as a task over [0, count).
class Slice : public BatchTask {
 public:
  Slice(BatchTask& task, std::size_t begin) : task_(task), begin_(begin) {}
  void EvaluateRange(std::size_t begin, std::size_t end) override {
    task_.EvaluateRange(begin_ + begin, begin_ + end);
  }
  std::vector<Buffer> Results() override { return {}; }

 private:
  BatchTask& task_;
  std::size_t begin_;
};

// An exception as bytes, to rebuild the same one on another rank: combabc::Error with all its
// parts, anything else as its what().
std::string Serialise(const std::exception_ptr& error) {
  std::string bytes;
  auto add = [&bytes](const std::string& s) {
    bytes += std::to_string(s.size()) + ':';
    bytes += s;
  };
  try {
    std::rethrow_exception(error);
  } catch (const Error& e) {
    add(std::to_string(static_cast<int>(e.kind())));
    add(e.message());
    add(e.file());
    add(std::to_string(e.line()));
    add(e.field());
    add(std::to_string(e.column()));
  } catch (const std::exception& e) {
    add("-1");
    add(e.what());
  } catch (...) {
    add("-1");
    add("unknown exception");
  }
  return bytes;
}

[[noreturn]] void ThrowSerialised(const std::string& bytes) {
  std::vector<std::string> parts;
  for (std::size_t at = 0; at < bytes.size();) {
    const std::size_t colon = bytes.find(':', at);
    const std::size_t length = std::stoul(bytes.substr(at, colon - at));
    parts.push_back(bytes.substr(colon + 1, length));
    at = colon + 1 + length;
  }
  if (parts.size() == 6 && parts[0] != "-1") {
    throw Error(static_cast<ErrorKind>(std::stoi(parts[0])),
                parts[1],
                parts[2],
                std::stoi(parts[3]),
                parts[4],
                std::stoi(parts[5]));
  }
  throw std::runtime_error(parts.size() >= 2 ? parts[1] : "unknown exception");
}

}  // namespace

MpiSession::MpiSession(int* argc, char*** argv) {
  int provided = 0;
  Check(MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided), "MPI_Init_thread");
  MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
}

MpiSession::~MpiSession() { MPI_Finalize(); }

bool MpiSession::LaunchedByMpirun() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE"}) {
    if (std::getenv(name) != nullptr) return true;
  }
  return false;
}

MpiExecutor::MpiExecutor(int threads) : local_(threads) {
  int initialised = 0;
  MPI_Initialized(&initialised);
  if (!initialised) throw std::logic_error("MpiExecutor needs an MpiSession (MPI_Init)");
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
}

void MpiExecutor::Execute(std::size_t n, BatchTask& task) {
  const std::size_t begin = SliceBegin(n, rank_, size_);
  const std::size_t end = SliceBegin(n, rank_ + 1, size_);
  std::exception_ptr error;
  try {
    Slice slice(task, begin);
    local_.Execute(end - begin, slice);
  } catch (...) {
    error = std::current_exception();
  }
  // Before the data: a rank whose slice failed still takes part, so none waits forever.
  Join(error);
  std::vector<int> counts(static_cast<std::size_t>(size_)), offsets(counts.size());
  for (const BatchTask::Buffer& buffer : task.Results()) {
    if (buffer.row_bytes == 0 || n == 0) continue;
    for (int r = 0; r < size_; ++r) {
      const std::size_t first = SliceBegin(n, r, size_), last = SliceBegin(n, r + 1, size_);
      if (n * buffer.row_bytes > static_cast<std::size_t>(INT_MAX)) {
        throw Error(ErrorKind::kSoftware,
                    "MPI: a batch of " + std::to_string(n) +
                        " candidates has more than 2 GiB "
                        "of results; use a smaller batch_size");
      }
      counts[static_cast<std::size_t>(r)] = static_cast<int>((last - first) * buffer.row_bytes);
      offsets[static_cast<std::size_t>(r)] = static_cast<int>(first * buffer.row_bytes);
    }
    Check(MPI_Allgatherv(MPI_IN_PLACE,
                         0,
                         MPI_DATATYPE_NULL,
                         buffer.data,
                         counts.data(),
                         offsets.data(),
                         MPI_BYTE,
                         MPI_COMM_WORLD),
          "MPI_Allgatherv");
  }
}

void MpiExecutor::Join(const std::exception_ptr& error) {
  // The lowest failing rank's error wins: the same one on every rank, whatever the timing.
  const int mine = error ? rank_ : size_;
  int first = size_;
  Check(MPI_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD), "MPI_Allreduce");
  if (first == size_) return;
  std::string bytes = rank_ == first ? Serialise(error) : std::string();
  auto length = static_cast<std::uint64_t>(bytes.size());
  Check(MPI_Bcast(&length, 1, MPI_UINT64_T, first, MPI_COMM_WORLD), "MPI_Bcast");
  bytes.resize(length);
  Check(MPI_Bcast(bytes.data(), static_cast<int>(length), MPI_CHAR, first, MPI_COMM_WORLD),
        "MPI_Bcast");
  if (rank_ == first) std::rethrow_exception(error);
  ThrowSerialised(bytes);
}

bool MpiExecutor::FromPrimary(bool value) {
  int flag = value ? 1 : 0;
  Check(MPI_Bcast(&flag, 1, MPI_INT, 0, MPI_COMM_WORLD), "MPI_Bcast");
  return flag != 0;
}

double MpiExecutor::FromPrimary(double value) {
  Check(MPI_Bcast(&value, 1, MPI_DOUBLE, 0, MPI_COMM_WORLD), "MPI_Bcast");
  return value;
}

int ExitCodeOfPrimary(int code) {
  int shared = code;
  if (MPI_Bcast(&shared, 1, MPI_INT, 0, MPI_COMM_WORLD) != MPI_SUCCESS) return code;
  return shared;
}

}  // namespace combabc::mpi
