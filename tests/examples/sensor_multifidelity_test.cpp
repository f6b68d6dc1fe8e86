// examples/sensor-multifidelity with CalculiX in the loop, reduced (its config.toml as shipped is
// about 1,300 ccx runs): the expensive model alone, on the example's 36 clamp bits with ties and
// prior-0 clamps, enumerated over three of its five tied pairs (clamps 9 + 27, 10 + 28, 11 + 29;
// 16 configurations, 8 ccx runs with prior mass), must put all the posterior mass on the truth the
// data were made from (clamps 9, 11, 27, 29 fixed; README.md). Skipped only when `ccx` is not on
// PATH (scripts/setup.sh installs calculix-ccx, so CI runs it).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <string>

#include "e2e/cli_runner.hpp"
#include "examples/calculix_support.hpp"

namespace combabc::testing {
namespace {

namespace fs = std::filesystem;

const fs::path kExamples = fs::path(COMBABC_SOURCE_DIR) / "examples";
const std::string kTruth = "000000001010000000000000001010000000";

class SensorMultiFidelity : public ::testing::Test {
 protected:
  SensorMultiFidelity() : root_("sensor-multifidelity") {}

  // The example's folder and model.py beside it, as config.toml finds it
  // ({config_dir}/../sensor-calculix/model.py).
  void SetUp() override {
    if (!ProgramOnPath("ccx")) {
      GTEST_SKIP() << "ccx (CalculiX) is not on PATH; scripts/setup.sh installs calculix-ccx";
    }
    fs::create_directories(dir() / "../sensor-calculix");
    fs::copy_file(kExamples / "sensor-calculix/model.py", dir() / "../sensor-calculix/model.py");
    for (const char* file : {"config.toml", "data.csv"}) {
      fs::copy_file(kExamples / "sensor-multifidelity" / file, dir() / file);
    }
  }

  fs::path dir() const { return root_.path() / "sensor-multifidelity"; }

  TempFolder root_;
};

// The prior and ties of config.toml with only the pairs 9 + 27, 10 + 28 and 11 + 29 calibrated:
// every other clamp free (prior 0), tied in one group.
std::string ThreePairs(std::string text) {
  std::string prior = "prior = [";
  std::string others;
  for (int k = 1; k <= 36; ++k) {
    const bool pair = (k >= 9 && k <= 11) || (k >= 27 && k <= 29);
    prior += std::string(k > 1 ? ", " : "") + (pair ? "0.5" : "0");
    if (!pair) others += (others.empty() ? "" : ", ") + std::to_string(k);
  }
  prior += "]";
  const std::string tie = "tie = [[9, 27], [10, 28], [11, 29], [" + others + "]]\n";
  const std::string before = text;
  text = std::regex_replace(text, std::regex(R"(prior = \[[^\]]*\])"), prior);
  text = std::regex_replace(text, std::regex(R"(tie = \[\[[\s\S]*?\]\]\n)"), tie);
  EXPECT_NE(text, before) << "config.toml's [sampler] prior / tie not found";
  return text;
}

TEST_F(SensorMultiFidelity, TheExpensiveModelsExactPosteriorIsTheTruth) {
  const fs::path config = dir() / "config.toml";
  const std::string text = ThreePairs(ReadFile(config));
  std::ofstream(config) << text;
  const auto r = RunCli(
      {"enumerate", config.string(), "-o", (dir() / "enum").string(), "--no-report", "-q"}, dir());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto rows = ReadCsv(dir() / "enum/history.enumeration/top_configurations.csv");
  // Header: rank,configuration,bits,prior,posterior,d_...; rows by decreasing posterior.
  ASSERT_GE(rows.size(), 3u);
  ASSERT_EQ(rows[1].size(), 6u);
  EXPECT_EQ(rows[1][2], kTruth);
  EXPECT_DOUBLE_EQ(std::stod(rows[1][4]), 1.0) << "the only configuration within the target";
  EXPECT_DOUBLE_EQ(std::stod(rows[2][4]), 0.0);
  // The truth's distance is the noise's (about 0.003), under the target 0.005.
  EXPECT_LT(std::stod(rows[1][5]), 0.005);
}

}  // namespace
}  // namespace combabc::testing
