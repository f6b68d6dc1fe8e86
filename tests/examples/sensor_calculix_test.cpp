// examples/sensor-calculix with CalculiX in the loop: the exact posterior over the example's four
// configurations (`combabc enumerate`, 4 ccx runs) and the ABC-SMC run as shipped (86 ccx runs)
// must both put most of their mass on the truth the data were made from (bits 10: clamps 9 + 27
// fixed, 10 + 28 free; generate_data.py), and the run draws no warning from the fit and sanity
// checks: this is tests/examples/posterior_test.cpp's check of this example, which does not run
// it a second time. Skipped only when `ccx` is not on PATH (scripts/setup.sh installs
// calculix-ccx, so CI runs it).
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "e2e/cli_runner.hpp"
#include "examples/calculix_support.hpp"

namespace combabc::testing {
namespace {

namespace fs = std::filesystem;

const fs::path kExample = fs::path(COMBABC_SOURCE_DIR) / "examples/sensor-calculix";

class SensorCalculix : public ::testing::Test {
 protected:
  SensorCalculix() : dir_("sensor-calculix") {}

  void SetUp() override {
    if (!ProgramOnPath("ccx")) {
      GTEST_SKIP() << "ccx (CalculiX) is not on PATH; scripts/setup.sh installs calculix-ccx";
    }
    for (const char* file : {"config.toml", "model.py", "data.csv"}) {
      fs::copy_file(kExample / file, dir_.path() / file);
    }
  }

  TempFolder dir_;
};

TEST_F(SensorCalculix, EnumerationPutsTheMassOnTheTruth) {
  const auto r = RunCli(
      {"enumerate", dir_ / "config.toml", "-o", dir_ / "enum", "--no-report", "-q"}, dir_.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto rows = ReadCsv(dir_.path() / "enum/history.enumeration/top_configurations.csv");
  // Header: rank,configuration,bits,prior,posterior,d_...; rows by decreasing posterior.
  ASSERT_GE(rows.size(), 2u);
  ASSERT_EQ(rows[1].size(), 6u);
  EXPECT_EQ(rows[1][2], "10");
  EXPECT_GT(std::stod(rows[1][4]), 0.9);
  // The truth's distance is the noise's (about 0.003); a wrong simulator would not come near it.
  EXPECT_LT(std::stod(rows[1][5]), 0.02);
}

TEST_F(SensorCalculix, TheShippedRunFindsTheTruthWithoutWarnings) {
  const auto r = RunCli({"run", dir_ / "config.toml", "--no-report", "-q"}, dir_.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // The checks print on stderr even with -q, one "severity [code]: message" line each.
  EXPECT_EQ(r.err.find("warning ["), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("checks: "), std::string::npos) << r.err;
  const auto e = RunCli({"export", dir_ / "results-calculix/history.sqlite", "-o", dir_ / "export"},
                        dir_.path());
  ASSERT_EQ(e.exit_code, 0) << e.err;
  // marginals.csv: wave,bit,name,prob_paper,prob_importance; the last wave's two rows last.
  const auto rows = ReadCsv(dir_.path() / "export/marginals.csv");
  ASSERT_GE(rows.size(), 3u);
  const auto& first = rows[rows.size() - 2];
  const auto& second = rows[rows.size() - 1];
  ASSERT_EQ(first.size(), 5u);
  EXPECT_EQ(first[1], "1");  // bits count from 1
  // Recovered as posterior_test.cpp means it: more than 0.4 from the prior's 0.5, the right way.
  EXPECT_GT(std::stod(first[4]), 0.9) << "clamps 9+27 are fixed in the truth";
  EXPECT_LT(std::stod(second[4]), 0.1) << "clamps 10+28 are free in the truth";
}

}  // namespace
}  // namespace combabc::testing
