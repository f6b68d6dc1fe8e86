// The mode-loss warning through the CLI (docs/algorithm.md, "Mode loss"): a Python worker whose
// data accept the even-parity patterns of three bits (prior P(1) = 0.2, 0.2, 0.5: 110 holds 0.04
// of the posterior), sampled with the logistic kernel, which cannot represent bit 3 = bit 1 xor
// bit 2 and loses 110. The warning is printed under wave 2's progress line, with the checks at the
// end and at the end of the answer; the independent kernel on the same problem warns of nothing.
// About 0.5 s a run.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <string>

#include "cli_runner.hpp"

namespace combabc::testing {
namespace {

namespace fs = std::filesystem;

// Two outputs: (1, 0) for an even number of set bits, (0, 1) for an odd one.
const char* const kWorker = R"(import sys
print("combabc-worker 2", 2, "parity 1.0", flush=True)
for line in sys.stdin:
    request_id, bits, *reals = line.split()
    odd = sum(int(b) for b in bits) % 2
    print(request_id, "ok", *(("0.0", "1.0") if odd else ("1.0", "0.0")), flush=True)
)";

const char* const kConfig = R"([simulator]
kind = "worker"
argv = ["python3", "{config_dir}/worker.py"]
[simulator.bits]
names = ["a", "b", "c"]
[simulator.outputs]
coordinates = [0.0, 1.0]
[data]
csv = "data.csv"
position_column = "position_m"
displacement_column = "value"
position_unit = "m"
displacement_unit = "m"
[metric]
[[metric.component]]
type = "least_squares"
window = [0.0, 1.0]
threshold = [0.5, 0.5, 0.5, 0.5]
[sampler]
waves = 4
accepted_per_wave = 300
seed = 1
prior = [0.2, 0.2, 0.5]
estimator = "importance"
[proposal]
kind = "KERNEL"
[output]
directory = "out-KERNEL"
)";

class ModeLossCli : public ::testing::Test {
 protected:
  CliResult Run(const std::string& kernel) {
    std::ofstream(dir_ / "worker.py") << kWorker;
    std::ofstream(dir_ / "data.csv") << "position_m,value\n0.0,1.0\n1.0,0.0\n";
    const fs::path config = dir_ / (kernel + ".toml");
    std::ofstream(config) << std::regex_replace(kConfig, std::regex("KERNEL"), kernel);
    return RunCli({"run", config, "--no-report", "-j", "1"}, dir_.path());
  }
  const TempFolder dir_{"e2e-mode-loss"};
};

TEST_F(ModeLossCli, TheLogisticKernelsLostPatternIsWarnedOnTheTerminal) {
  const CliResult r = Run("logistic");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string warning = "wave 2 proposed pattern 110 (mass ";
  const std::size_t line = r.err.find("warning: " + warning);
  ASSERT_NE(line, std::string::npos) << r.err;
  EXPECT_LT(r.err.find("wave 2: eps"), line) << r.err;
  EXPECT_LT(line, r.err.find("wave 3: eps")) << r.err;
  EXPECT_NE(r.err.find("the posterior may have lost a mode"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("warning [mode_loss]: " + warning), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("warning: " + warning), std::string::npos) << r.out;
  // And lost it is: the answer's configurations hold the three other even patterns only.
  EXPECT_NE(r.out.find("(3 distinct)"), std::string::npos) << r.out;
}

TEST_F(ModeLossCli, TheIndependentKernelKeepsItAndWarnsOfNothing) {
  const CliResult r = Run("independent");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("lost a mode"), std::string::npos) << r.err;
  EXPECT_EQ(r.out.find("lost a mode"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("(4 distinct)"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace combabc::testing
