// Per-call overhead of the external simulators (issue 10) with a trivial simulator, so that what
// is timed is combabc's side plus the operating system's: a worker round trip (one request line
// out, one response line back) and a command call (new folder, parameters file, process spawn in
// its own group, stdout read, wait, folder removed). The trivial simulator is this program itself,
// run with --as-worker / --as-command, and /bin/echo for the bare spawn.
#include <benchmark/benchmark.h>
#include <fcntl.h>
#include <sched.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <string>
#include <thread>

#include "combabc/simulators/command_simulator.hpp"
#include "combabc/simulators/worker_simulator.hpp"

extern "C" char** environ;  // NOLINT(readability-redundant-declaration)

namespace {

namespace fs = std::filesystem;
std::string self_path;  // NOLINT: set once in main, before any benchmark

constexpr int kOutputs = 3;

bool PinTo(int cpu) {
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  return ::sched_setaffinity(0, sizeof set, &set) == 0;
}

// With a CPU number, the worker pins itself there (the cross-core benchmark below).
int RunAsWorker(const char* cpu) {
  if (cpu != nullptr) PinTo(std::atoi(cpu));
  std::printf("combabc-worker 2 %d bench-trivial\n", kOutputs);
  std::fflush(stdout);
  char line[4096];
  while (std::fgets(static_cast<char*>(line), sizeof line, stdin) != nullptr) {
    // The answer starts with the request's id, the request's first word.
    line[std::strcspn(static_cast<const char*>(line), " \n")] = '\0';
    std::printf("%s ok 1 2 3\n", static_cast<const char*>(line));
    std::fflush(stdout);
  }
  return 0;
}

int RunAsCommand() {
  std::fputs("1\n2\n3\n", stdout);
  return 0;
}

combabc::ExternalSimulatorOptions Options(const std::string& work) {
  combabc::ExternalSimulatorOptions o;
  o.work_directory = work;
  o.bit_names.assign(36, "b");
  o.output_size = kOutputs;
  o.timeout_s = 10.0;
  return o;
}

struct Scratch {
  fs::path path = fs::temp_directory_path() / ("combabc-bench-" + std::to_string(::getpid()));
  Scratch() { fs::create_directories(path); }
  ~Scratch() { fs::remove_all(path); }
  Scratch(const Scratch&) = delete;
  Scratch& operator=(const Scratch&) = delete;
};

void Call(benchmark::State& state, const combabc::Simulator& simulator) {
  std::vector<std::uint8_t> bits(36, 1);
  std::vector<double> reals;
  std::vector<double> out(kOutputs);
  combabc::RandomStream rng(1, 0, 0);
  for (auto _ : state) {
    simulator.Simulate({bits, reals}, rng, out);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_WorkerRoundTrip(benchmark::State& state) {
  const Scratch scratch;
  auto o = Options((scratch.path / "work").string());
  o.argv = {self_path, "--as-worker"};
  const combabc::WorkerSimulator worker(o);
  Call(state, worker);
}
BENCHMARK(BM_WorkerRoundTrip)->Unit(benchmark::kMicrosecond)->UseRealTime();

// The same with combabc's thread on CPU 0 and the worker on CPU 1: the scheduler may otherwise put
// both on one core, where the exchange is a cheap context switch. Across cores each side's wake-up
// reaches a CPU that may have gone idle, which on a virtual machine costs tens of microseconds.
void BM_WorkerRoundTripCrossCore(benchmark::State& state) {
  cpu_set_t before;
  ::sched_getaffinity(0, sizeof before, &before);
  if (std::thread::hardware_concurrency() < 2 || !PinTo(0)) {
    state.SkipWithError("needs two CPUs");
    return;
  }
  {
    const Scratch scratch;
    auto o = Options((scratch.path / "work").string());
    o.argv = {self_path, "--as-worker", "1"};
    const combabc::WorkerSimulator worker(o);
    Call(state, worker);
  }
  ::sched_setaffinity(0, sizeof before, &before);
}
BENCHMARK(BM_WorkerRoundTripCrossCore)->Unit(benchmark::kMicrosecond)->UseRealTime();

// The realistic call: parameters file (JSON), a program that reads nothing and prints 3 values.
void BM_CommandCall(benchmark::State& state) {
  const Scratch scratch;
  auto o = Options((scratch.path / "work").string());
  o.argv = {self_path, "--as-command", "{params}"};
  const combabc::CommandSimulator command(o);
  Call(state, command);
}
BENCHMARK(BM_CommandCall)->Unit(benchmark::kMicrosecond)->UseRealTime();

// The smallest program there is (/bin/echo, parameters on stdin): the spawn itself.
void BM_CommandCallEcho(benchmark::State& state) {
  const Scratch scratch;
  auto o = Options((scratch.path / "work").string());
  o.argv = {"/bin/echo", "1", "2", "3"};
  o.params = combabc::Transport::kStdin;
  const combabc::CommandSimulator command(o);
  Call(state, command);
}
BENCHMARK(BM_CommandCallEcho)->Unit(benchmark::kMicrosecond)->UseRealTime();

// The floor: posix_spawn of /bin/echo and waitpid, nothing else (no pipes, folder or group).
void BM_BareSpawnEcho(benchmark::State& state) {
  char echo[] = "/bin/echo";
  char* argv[] = {static_cast<char*>(echo), nullptr};
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  for (auto _ : state) {
    pid_t pid = 0;
    if (::posix_spawn(&pid, echo, &actions, nullptr, static_cast<char**>(argv), environ) != 0) {
      state.SkipWithError("posix_spawn failed");
      break;
    }
    int status = 0;
    ::waitpid(pid, &status, 0);
  }
  posix_spawn_file_actions_destroy(&actions);
}
BENCHMARK(BM_BareSpawnEcho)->Unit(benchmark::kMicrosecond)->UseRealTime();

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 2 && std::strcmp(argv[1], "--as-worker") == 0) {
    return RunAsWorker(argc >= 3 ? argv[2] : nullptr);
  }
  if (argc >= 2 && std::strcmp(argv[1], "--as-command") == 0) return RunAsCommand();
  self_path = fs::canonical("/proc/self/exe").string();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
