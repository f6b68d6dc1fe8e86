// libFuzzer target: the reader of a worker's answers (protocol combabc-worker 2,
// docs/simulators.md), simulators_internal::ReadResponse, on a session: the bytes are what a
// worker wrote to its stdout, split into lines, and line k is read as the answer to request k, as
// WorkerSimulator does, up to the first line that leaves the worker out of step (WorkerSimulator
// would kill it there). Seeds: fuzz/corpus/worker_answer/; dictionary: fuzz/worker_answer.dict.
//
// Input layout: the first byte's low three bits plus one are the output count (so a seed starts
// with "0" for 1 output, "2" for 3), the rest is the worker's stdout.
//
// ReadResponse reports every problem in its return value (the candidate's failure reason); any
// exception escaping it is a finding, and so is a broken promise (CheckAnswer aborts): an answer
// accepted without being in step, or with values that are not finite, or one whose id is not the
// request's; a reason that is empty when the worker is out of step, or that is not one printable
// line (it is stored in the history and printed).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "simulators/simulator_io.hpp"

namespace {

void Check(bool ok, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "worker_answer_fuzzer: broken promise: %s\n", what);
    std::abort();
  }
}

// Reads `line` as the answer to request `id`; false when the worker is out of step.
bool CheckAnswer(std::string_view line, std::uint64_t id, std::span<double> out) {
  for (double& v : out) v = -1.0;
  bool in_step = true;
  const std::string reason = combabc::simulators_internal::ReadResponse(line, id, out, &in_step);
  for (const char c : reason) {
    Check(static_cast<unsigned char>(c) >= 0x20 && c != 0x7f, "the reason is one printable line");
  }
  if (!in_step) {
    Check(!reason.empty(), "a worker out of step fails the candidate");
    return false;
  }
  const std::string prefix = std::to_string(id) + " ";
  Check(line.substr(0, prefix.size()) == prefix, "an answer in step carries the request's id");
  if (reason.empty()) {
    Check(line.substr(prefix.size(), 2) == "ok", "only \"ok\" answers give values");
    for (const double v : out) Check(std::isfinite(v), "accepted values are finite");
  }
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  std::vector<double> out(static_cast<std::size_t>(data[0] & 7) + 1);
  const std::string_view text(reinterpret_cast<const char*>(data) + 1, size - 1);
  std::uint64_t id = 1;
  std::size_t begin = 0;
  while (begin < text.size()) {
    const std::size_t end = text.find('\n', begin);
    if (end == std::string_view::npos) break;  // a partial line: WorkerSimulator's end of file
    if (!CheckAnswer(text.substr(begin, end - begin), id, out)) break;
    ++id;
    begin = end + 1;
  }
  return 0;
}
