// Hostile input through the CLI: signals at every stage, oversized files, sizes that would exhaust
// memory, extreme numbers, control characters. Each refusal is one stderr line with the sysexits
// code; nothing hangs, nothing crashes.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

#include "cli_runner.hpp"

namespace combabc::testing {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

constexpr int kUsage = 64, kData = 65, kConfig = 78, kInterrupted = 130;

const char* kConfigText = R"([data]
csv = "data.csv"
position_column = "x_cm"
displacement_column = "w_m"
window = [48, 80]

[metric]
preset = "least_squares"

[sampler]
waves = 2
accepted_per_wave = 20

[output]
directory = "out"
)";

std::string GoodCsv() {
  std::string csv = "x_cm,w_m\n";
  for (int x = 48; x <= 80; ++x) {
    csv += std::to_string(x) + "," + std::to_string(1e-6 / (1.0 + (x - 48) * 0.2)) + "\n";
  }
  return csv;
}

// Waits at most `limit` for the child; kills it (and fails) if it does not end.
CliResult WaitAtMost(pid_t pid, const fs::path& dir, std::chrono::seconds limit) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  int status = 0;
  while (::waitpid(pid, &status, WNOHANG) == 0) {
    if (std::chrono::steady_clock::now() > deadline) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      ADD_FAILURE() << "the CLI did not end within " << limit.count() << " s";
      break;
    }
    std::this_thread::sleep_for(20ms);
  }
  CliResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.out = ReadFile(dir / "cli.stdout");
  r.err = ReadFile(dir / "cli.stderr");
  return r;
}

class InputLimits : public ::testing::Test {
 protected:
  InputLimits()
      : dir_("input-limits-" +
             std::string(::testing::UnitTest::GetInstance()->current_test_info()->name())) {
    Write("config.toml", kConfigText);
    Write("data.csv", GoodCsv());
  }
  void Write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name, std::ios::binary) << text;
  }
  static std::string Replace(std::string text, const std::string& from, const std::string& to) {
    const auto at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return text.replace(at, from.size(), to);
  }
  // The common contract of a refusal: exit code, one stderr line, no history left behind.
  std::string Expect(const std::vector<std::string>& args, int code) {
    const auto r = WaitAtMost(SpawnCli(args, dir_.path()), dir_.path(), 60s);
    EXPECT_EQ(r.exit_code, code) << r.err;
    EXPECT_EQ(CountLines(r.err), 1) << r.err;
    EXPECT_FALSE(fs::exists(dir_.path() / "out" / "history.sqlite")) << "history left behind";
    return r.err;
  }
  // Starts a run whose single wave cannot finish soon, and signals it once sampling is under way
  // (the history exists and a moment has passed for the model precompute to end).
  CliResult InterruptLongRun(std::vector<std::string> extra_args, int signal_number) {
    Write("config.toml",
          Replace(Replace(kConfigText, "waves = 2", "waves = 1"),
                  "accepted_per_wave = 20",
                  "accepted_per_wave = 100000000\nbatch_size = 64"));
    std::vector<std::string> args = {"run", config(), "--no-report"};
    args.insert(args.end(), extra_args.begin(), extra_args.end());
    const pid_t pid = SpawnCli(args, dir_.path());
    const auto deadline = std::chrono::steady_clock::now() + 60s;
    while (!fs::exists(dir_.path() / "out" / "history.sqlite") &&
           std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(20ms);
    }
    std::this_thread::sleep_for(1500ms);
    ::kill(pid, signal_number);
    return WaitAtMost(pid, dir_.path(), 60s);
  }
  std::string config() const { return dir_ / "config.toml"; }
  ScratchDir dir_;
};

// Regression: with -q the progress display (which polled the interrupt flag) was absent and
// SIGINT / SIGTERM were ignored.
TEST_F(InputLimits, QuietRunStopsResumablyOnSigterm) {
  const auto r = InterruptLongRun({"-q"}, SIGTERM);
  EXPECT_EQ(r.exit_code, kInterrupted) << r.err;
  EXPECT_NE(r.err.find("combabc resume"), std::string::npos) << r.err;
}

TEST_F(InputLimits, QuietRunStopsResumablyOnSigint) {
  const auto r = InterruptLongRun({"-q"}, SIGINT);
  EXPECT_EQ(r.exit_code, kInterrupted) << r.err;
}

TEST_F(InputLimits, RunWithProgressStopsResumablyOnSigint) {
  const auto r = InterruptLongRun({}, SIGINT);
  EXPECT_EQ(r.exit_code, kInterrupted) << r.err;
  EXPECT_NE(r.err.find("combabc resume"), std::string::npos) << r.err;
}

// Regression: the handler was installed before the config was read, so a run blocked on a FIFO
// nobody writes to ignored SIGTERM.
TEST_F(InputLimits, BlockedOnAFifoConfigIsKillable) {
  const std::string fifo = dir_ / "config.fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  for (const int signal_number : {SIGTERM, SIGINT}) {
    const pid_t pid = SpawnCli({"run", fifo}, dir_.path());
    std::this_thread::sleep_for(300ms);
    ::kill(pid, signal_number);
    const auto r = WaitAtMost(pid, dir_.path(), 10s);
    EXPECT_EQ(r.exit_code, 128 + signal_number) << r.err;
  }
}

// Regression: a negative thread count was accepted (and silently meant "the config's").
TEST_F(InputLimits, NegativeThreadCountIsAUsageError) {
  auto err = Expect({"run", "-j", "-3", config()}, kUsage);
  EXPECT_NE(err.find("--threads"), std::string::npos) << err;
  err = Expect({"resume", "-j", "-1", dir_ / "run.sqlite"}, kUsage);
  EXPECT_NE(err.find("--threads"), std::string::npos) << err;
  Write("config.toml", Replace(kConfigText, "waves = 2", "waves = 2\nthreads = -3"));
  err = Expect({"run", config()}, kConfig);
  EXPECT_NE(err.find("sampler.threads"), std::string::npos) << err;
}

// Regression: `run /dev/zero` read without bound (8.8 GB before the OOM killer).
TEST_F(InputLimits, EndlessOrOversizedConfigIsRefusedWhileReading) {
  auto err = Expect({"run", "/dev/zero"}, kConfig);
  EXPECT_NE(err.find("/dev/zero: config file is larger than the 1 MiB limit"), std::string::npos)
      << err;
  Write("big.toml", std::string(kConfigText) + "# " + std::string(1 << 20, 'x') + "\n");
  err = Expect({"run", dir_ / "big.toml"}, kConfig);
  EXPECT_NE(err.find("1 MiB"), std::string::npos) << err;
}

TEST_F(InputLimits, EndlessOrOversizedCsvIsRefusedWhileReading) {
  Write("config.toml", Replace(kConfigText, "csv = \"data.csv\"", "csv = \"/dev/zero\""));
  auto err = Expect({"run", config()}, kData);
  EXPECT_NE(err.find("/dev/zero: data file is larger than the 64 MiB limit"), std::string::npos)
      << err;
  std::string big = GoodCsv();
  big += "# " + std::string((std::size_t{64} << 20) - big.size(), 'x') + "\n";
  Write("data.csv", big);
  Write("config.toml", kConfigText);
  err = Expect({"run", config()}, kData);
  EXPECT_NE(err.find("data.csv: data file is larger than the 64 MiB limit"), std::string::npos)
      << err;
}

// Regression: errors echoed raw input, so a config or CSV could drive the user's terminal.
TEST_F(InputLimits, ErrorsEscapeControlCharactersAndQuoteOnlyExcerpts) {
  Write("config.toml",
        Replace(kConfigText, "window = [48, 80]", "position_unit = \"\\u001b[2J\\u0000cm\""));
  auto err = Expect({"run", config()}, kConfig);
  EXPECT_EQ(err.find('\x1b'), std::string::npos) << err;
  EXPECT_NE(err.find("data.position_unit: unknown unit '\\x1b[2J\\0cm'"), std::string::npos) << err;

  Write("config.toml", kConfigText);
  Write("data.csv", Replace(GoodCsv(), "50,", "50," + std::string(5000, 'z') + "\x1b[31m\r\n51,"));
  err = Expect({"run", config()}, kData);
  EXPECT_EQ(err.find('\x1b'), std::string::npos) << err;
  EXPECT_NE(err.find("data.csv:4:2: w_m: not a number: 'zzz"), std::string::npos) << err;
  EXPECT_LT(err.size(), 300u) << err;
}

}  // namespace
}  // namespace combabc::testing
