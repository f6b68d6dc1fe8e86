#pragma once
// Helpers for the external-simulator tests: a scratch run folder (with a space and shell
// metacharacters in its path), options for a sh script, and checks that nothing is left behind.
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "combabc/params/parameter_value.hpp"
#include "combabc/rng/random_stream.hpp"
#include "combabc/simulators/external_simulator.hpp"
#include "support/test_support.hpp"

namespace combabc::testing {

namespace fs = std::filesystem;

// A TempFolder whose path holds a space and shell metacharacters: a simulator that hands a path to
// a shell unquoted runs `touch pwned` or breaks.
class RunFolder : public TempFolder {
 public:
  explicit RunFolder(const std::string& name) : TempFolder("sim $(touch pwned); " + name) {}
};

// Options for `sh -c script sh [args...]`, 3 bits, no reals, `outputs` outputs.
inline ExternalSimulatorOptions ShOptions(const RunFolder& run,
                                          const std::string& script,
                                          std::vector<std::string> args = {},
                                          int outputs = 3) {
  ExternalSimulatorOptions o;
  o.argv = {"sh", "-c", script, "sh"};
  o.argv.insert(o.argv.end(), args.begin(), args.end());
  o.config_directory = run.path().string();
  o.work_directory = run / "history.work";
  o.bit_names = {"b1", "b2", "b3"};
  o.output_size = outputs;
  o.timeout_s = 5.0;
  return o;
}

struct Candidate {
  std::vector<std::uint8_t> bits;
  std::vector<double> reals;
  ParameterView view() const { return {bits, reals}; }
};

inline Candidate Bits(const std::string& text, std::vector<double> reals = {}) {
  Candidate c;
  for (char ch : text) c.bits.push_back(ch == '1' ? 1 : 0);
  c.reals = std::move(reals);
  return c;
}

inline std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// True once no process with this pid runs (polled: an orphan is reaped by init, not by us, and an
// init that does not reap leaves a zombie, which is dead all the same).
inline bool Gone(pid_t pid) {
  for (int i = 0; i < 200; ++i) {
    if (::kill(pid, 0) != 0) return true;
    const std::string stat = ReadText("/proc/" + std::to_string(pid) + "/stat");
    const std::size_t paren = stat.rfind(')');
    if (paren != std::string::npos && paren + 2 < stat.size() && stat[paren + 2] == 'Z') {
      return true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

// Entries of a folder (empty when it does not exist).
inline std::vector<std::string> Entries(const fs::path& dir) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) names.push_back(e.path().filename());
  return names;
}

}  // namespace combabc::testing
