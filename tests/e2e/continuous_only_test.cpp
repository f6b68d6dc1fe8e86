// A continuous-only run through the CLI: a command simulator (awk, one process per candidate)
// with [parameters.mu] and no [simulator.bits]; run, verify, export and report, and the answer
// names the real and prints no bit table. Tiny (3 waves of 30, about 220 simulations).
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "cli_runner.hpp"

namespace combabc::testing {
namespace {

namespace fs = std::filesystem;

// y(x) = mu + 2 x on 11 positions; the data: mu = 0.5 with 1 % noise.
const std::string kConfig = R"(description = "continuous only"
[simulator]
kind = "command"
argv = ["awk", "-F,", "$1 == \"mu\" { v = $2 } END { for (k = 0; k <= 10; k++) print v + 0.04 * k }",
        "{params}"]
params_format = "csv"
[simulator.outputs]
name = "y"
coordinates = [0.0, 0.02, 0.04, 0.06, 0.08, 0.1, 0.12, 0.14, 0.16, 0.18, 0.2]
[data]
csv = "data.csv"
position_unit = "m"
[metric]
[[metric.component]]
type = "least_squares"
window = [0.0, 0.2]
[sampler]
waves = 3
accepted_per_wave = 30
estimator = "importance"
seed = 3
[parameters.mu]
prior = "normal"
mean = 0.0
sd = 1.0
[output]
directory = "out"
)";

const std::string kData =
    "position,displacement\n0.00,0.4837\n0.02,0.5373\n0.04,0.5773\n0.06,0.6226\n0.08,0.6645\n"
    "0.10,0.7021\n0.12,0.7452\n0.14,0.7862\n0.16,0.8168\n0.18,0.8646\n0.20,0.9016\n";

class ContinuousOnlyRun : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempFolder("e2e-continuous-only");
    std::ofstream(*dir_ / "run.toml") << kConfig;
    std::ofstream(*dir_ / "data.csv") << kData;
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

TempFolder* ContinuousOnlyRun::dir_ = nullptr;
CliResult* ContinuousOnlyRun::run_ = nullptr;

TEST_F(ContinuousOnlyRun, TheAnswerNamesTheRealAndHasNoBitTable) {
  const std::string& out = run_->out;
  EXPECT_NE(out.find(" mu         "), std::string::npos) << out;
  EXPECT_NE(out.find("posterior mean ± standard error, sd"), std::string::npos) << out;
  EXPECT_EQ(out.find("P(bit = 1)"), std::string::npos) << out;
  EXPECT_EQ(out.find("configurations"), std::string::npos) << out;
  EXPECT_EQ(out.find("distinct"), std::string::npos) << out;
}

TEST_F(ContinuousOnlyRun, VerifiesAndExportsARealsColumnAndNoBitRows) {
  const auto v = RunCli({"verify", History()}, dir_->path());
  EXPECT_EQ(v.exit_code, 0) << v.err;
  EXPECT_NE(v.out.find("OK"), std::string::npos) << v.out;
  const auto r = RunCli({"export", History()}, dir_->path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string particles = ReadFile(*dir_ / "out/export/particles.csv");
  EXPECT_EQ(particles.rfind("wave,index,bits,mu,log_weight,weight,", 0), 0u) << particles;
  EXPECT_EQ(CountLines(particles), 1 + 3 * 30);
  // The marginals' and pair correlations' files keep their header, with no rows.
  EXPECT_EQ(CountLines(ReadFile(*dir_ / "out/export/marginals.csv")), 1);
  EXPECT_EQ(CountLines(ReadFile(*dir_ / "out/export/pair_correlations.csv")), 1);
  const std::string summary = ReadFile(*dir_ / "out/export/summary.json");
  EXPECT_NE(summary.find("\"reals\": [\n      {\"name\": \"mu\", \"mean\": "), std::string::npos)
      << summary;
}

TEST_F(ContinuousOnlyRun, Reports) {
  if (std::system("/usr/bin/python3 -c 'import numpy, matplotlib' > /dev/null 2>&1") != 0) {
    GTEST_SKIP() << "/usr/bin/python3 lacks numpy or matplotlib (scripts/setup.sh installs them)";
  }
  const auto r = RunCli({"report", History(), "-o", *dir_ / "report"}, dir_->path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::exists(*dir_ / "report/reals.png"));
  EXPECT_FALSE(fs::exists(*dir_ / "report/wave_1_marginals.png"));
  EXPECT_NE(ReadFile(*dir_ / "report/index.html").find("Continuous parameters"), std::string::npos);
}

}  // namespace
}  // namespace combabc::testing
