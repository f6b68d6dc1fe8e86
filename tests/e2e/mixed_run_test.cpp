// A mixed run (clamps and a continuous unknown) through the CLI: run, then verify, export and
// report the result, and resume a run started with the same inputs to the same history.
// Tiny (3 + 3 clamps, a 2 x 2 mesh per section, 3 waves of 30), so it stays a unit test.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <utility>

#include "cli_runner.hpp"
#include "combabc/history/history_store.hpp"
#include "tiny_sensor.hpp"

namespace combabc::testing {
namespace {

namespace fs = std::filesystem;

constexpr double kLow = 2e4;  // N/m^3, the uniform prior's support
constexpr double kHigh = 2e5;

const std::string kConfig = TinySensorConfig(
    "seed = 5\nwaves = 3\naccepted_per_wave = 30\nestimator = \"importance\"\n", R"([proposal]
kind = "logistic"

[parameters.foundation_stiffness]
prior = "uniform"
low = 2e4
high = 2e5

[output]
directory = "out"
)");

// Splits one CSV line (the export writes no quoted commas in these files).
std::vector<std::string> Fields(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream s(line);
  std::string field;
  while (std::getline(s, field, ',')) fields.push_back(field);
  return fields;
}

class MixedRun : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempFolder("e2e-mixed");
    std::ofstream(*dir_ / "run.toml") << kConfig;
    WriteTinySensorData(dir_->path());
    run_ = new CliResult(RunCli({"run", *dir_ / "run.toml", "--no-report"}, dir_->path()));
  }
  static void TearDownTestSuite() {
    delete run_;
    delete dir_;
  }
  void SetUp() override { ASSERT_EQ(run_->exit_code, 0) << run_->err; }

  static std::string History() { return *dir_ / "out/history.sqlite"; }

  static TempFolder* dir_;
  static CliResult* run_;
};

TempFolder* MixedRun::dir_ = nullptr;
CliResult* MixedRun::run_ = nullptr;

TEST_F(MixedRun, VerifiesSound) {
  const auto r = RunCli({"verify", History()}, dir_->path());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("OK"), std::string::npos) << r.out;
}

TEST_F(MixedRun, ExportsTheRealsColumnWithValuesInsideThePriorsSupport) {
  const auto r = RunCli({"export", History()}, dir_->path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in(*dir_ / "out/export/particles.csv");
  std::string line;
  ASSERT_TRUE(std::getline(in, line));
  const std::vector<std::string> header = Fields(line);
  std::size_t column = header.size();
  for (std::size_t c = 0; c < header.size(); ++c) {
    if (header[c] == "foundation_stiffness") column = c;
  }
  ASSERT_LT(column, header.size()) << line;
  int rows = 0;
  double lowest = kHigh, highest = kLow;
  while (std::getline(in, line)) {
    const std::vector<std::string> fields = Fields(line);
    ASSERT_EQ(fields.size(), header.size()) << line;
    const double value = std::stod(fields[column]);
    EXPECT_GE(value, kLow) << line;
    EXPECT_LE(value, kHigh) << line;
    lowest = std::min(lowest, value);
    highest = std::max(highest, value);
    ++rows;
  }
  EXPECT_EQ(rows, 3 * 30);
  // Drawn values, not one constant: the prior's wave alone spreads over most of the support.
  EXPECT_GT(highest - lowest, 0.3 * (kHigh - kLow));
  std::ifstream waves(*dir_ / "out/export/waves.csv");
  ASSERT_TRUE(std::getline(waves, line));
  EXPECT_NE(line.find("foundation_stiffness_mean,foundation_stiffness_sd"), std::string::npos)
      << line;
}

// Resuming a run that was started with this run's inputs (and stopped before its first batch)
// gives the finished run's history: every deterministic field equal (SameHistory; the waves'
// stored checksums also cover their start and end times, so they differ) and the exported
// particles byte for byte. The finished run itself is not re-run.
TEST_F(MixedRun, ResumeReproducesTheHistoryAndItsExport) {
  const std::string started = *dir_ / "started.sqlite";
  HistoryStore::Create(started, HistoryStore::Open(History(), true).LoadMetadata());
  const auto r = RunCli({"resume", started, "--no-report", "-j", "2"}, dir_->path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const RunHistory finished = HistoryStore::Open(History(), true).LoadHistory();
  ASSERT_EQ(finished.waves.size(), 3u);
  std::string where;
  EXPECT_TRUE(SameHistory(finished, HistoryStore::Open(started, true).LoadHistory(), &where))
      << where;
  for (const auto& [history, out] : {std::pair{History(), *dir_ / "export-finished"},
                                     std::pair{started, *dir_ / "export-resumed"}}) {
    const auto e = RunCli({"export", history, "-o", out}, dir_->path());
    ASSERT_EQ(e.exit_code, 0) << e.err;
  }
  const std::string particles = ReadFile(*dir_ / "export-finished/particles.csv");
  EXPECT_EQ(CountLines(particles), 1 + 3 * 30);
  EXPECT_EQ(ReadFile(*dir_ / "export-resumed/particles.csv"), particles);
  EXPECT_EQ(RunCli({"resume", History()}, dir_->path()).exit_code, 64);
}

TEST_F(MixedRun, Reports) {
  if (std::system("/usr/bin/python3 -c 'import numpy, matplotlib' > /dev/null 2>&1") != 0) {
    GTEST_SKIP() << "/usr/bin/python3 lacks numpy or matplotlib (scripts/setup.sh installs them)";
  }
  const auto r = RunCli({"report", History()}, dir_->path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir_->path() / "out/report/index.html")) << r.out;
}

}  // namespace
}  // namespace combabc::testing
