// `combabc enumerate` through the CLI: on the 45 cm example reduced to 5 + 5 clamps (2^10
// configurations, well under a second) it writes a one-wave history that verify, export and
// report read unchanged, and its tables; thresholds default to the config's final ones.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "cli_runner.hpp"
#include "output_test_support.hpp"
#include "tiny_sensor.hpp"

namespace combabc::testing {
namespace {

namespace fs = std::filesystem;

constexpr int kUsage = 64, kCantCreate = 73, kConfig = 78;

void Replace(std::string& text, const std::string& line_start, const std::string& with) {
  const auto at = text.find("\n" + line_start);
  ASSERT_NE(at, std::string::npos) << line_start;
  const auto end = text.find('\n', at + 1);
  text.replace(at + 1, end - at - 1, with);
}

// The shipped example with 5 clamps per edge and `schedule` as its [metric] threshold schedule.
std::string Config(const std::string& schedule) {
  std::string text = ReadFile(fs::path(COMBABC_SOURCE_DIR) / "examples/sensor-45cm/area.toml");
  Replace(text, "per_edge =", "per_edge = 5");
  Replace(text, "quantile =", schedule);
  Replace(text, "waves =", "waves = 2");
  Replace(text, "threads =", "threads = 2");
  Replace(text, "directory =", "directory = \"out\"");
  return text;
}

int Lines(const std::string& s) { return CountLines(s); }

TEST(Enumerate, WritesAHistoryThatVerifyExportAndReportRead) {
  TempFolder dir("enumerate");
  fs::copy_file(fs::path(COMBABC_SOURCE_DIR) / "examples/sensor-45cm/data.csv", dir / "data.csv");
  std::ofstream(dir / "list.toml") << Config("threshold = [0.5, 0.3]");
  auto r = RunCli({"enumerate", dir / "list.toml", "--no-report", "-q", "--top", "7"}, dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("enumerated 1024 configurations"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("answer:"), std::string::npos) << "-q keeps the answer quiet: " << r.out;
  // The checks on stderr (issue 22, item 2): the data, then the fit of the accepted
  // configurations against the noise; no warning of the prior predictive's (finite thresholds).
  EXPECT_NE(r.err.find("checks: 33 measured points"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("first wave's accepted curves"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("best fit RMS"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;
  // In its own folder inside [output] directory, apart from `combabc run`'s history.
  const std::string history = dir / "out/enumeration/history.sqlite";
  ASSERT_TRUE(fs::exists(history)) << r.out;

  r = RunCli({"verify", history}, dir.path());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  r = RunCli({"export", history}, dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string waves = ReadFile(dir.path() / "out/enumeration/export/waves.csv");
  // One wave at the list's last threshold, every configuration a candidate.
  ASSERT_EQ(Lines(waves), 2) << waves;
  EXPECT_EQ(waves.find("\n1,0.3,0,1024,"), waves.find('\n')) << waves;
  const std::string summary = ReadFile(dir.path() / "out/enumeration/export/summary.json");
  EXPECT_NE(summary.find("\"termination\": \"enumerated\""), std::string::npos);
  const std::string marginals = ReadFile(dir.path() / "out/enumeration/export/marginals.csv");
  EXPECT_EQ(Lines(marginals), 11);

  const std::string top =
      ReadFile(dir.path() / "out/enumeration/history.enumeration/top_configurations.csv");
  EXPECT_EQ(Lines(top), 8) << top;
  const std::string corr =
      ReadFile(dir.path() / "out/enumeration/history.enumeration/pair_correlations.csv");
  EXPECT_EQ(Lines(corr), 11) << corr;
  EXPECT_EQ(corr.find("nan"), std::string::npos) << corr;

  // A finished enumeration is not an SMC run to resume; and nothing is replaced unasked.
  r = RunCli({"resume", history, "--no-report"}, dir.path());
  EXPECT_EQ(r.exit_code, kUsage) << r.err;
  r = RunCli({"enumerate", dir / "list.toml", "--no-report", "-q"}, dir.path());
  EXPECT_EQ(r.exit_code, kCantCreate) << r.err;
  EXPECT_EQ(Lines(r.err), 1) << r.err;
  // The refusal says what to do instead (issue 22, item 8).
  EXPECT_NE(r.err.find("use --overwrite"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("-o DIR"), std::string::npos) << r.err;
  r = RunCli(
      {"enumerate", dir / "list.toml", "--no-report", "-q", "--overwrite", "--threshold", "0.2"},
      dir.path());
  EXPECT_EQ(r.exit_code, 0) << r.err;

  if (std::system("/usr/bin/python3 -c 'import numpy, matplotlib' > /dev/null 2>&1") == 0) {
    r = RunCli({"report", history}, dir.path());
    EXPECT_EQ(r.exit_code, 0) << r.err;
    EXPECT_TRUE(fs::exists(dir.path() / "out/enumeration/report/index.html"));
  }
}

TEST(Enumerate, WithoutAFinalThresholdAsksForOne) {
  TempFolder dir("enumerate-usage");
  fs::copy_file(fs::path(COMBABC_SOURCE_DIR) / "examples/sensor-45cm/data.csv", dir / "data.csv");
  std::ofstream(dir / "quantile.toml") << Config("quantile = 0.3");
  const auto r = RunCli({"enumerate", dir / "quantile.toml", "--no-report", "-q"}, dir.path());
  EXPECT_EQ(r.exit_code, kUsage) << r.err;
  EXPECT_EQ(Lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("--threshold"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir.path() / "out"));
}

// Regression (issue 22, item 8): `run` then `enumerate` on one config, without flags, wrote the
// same history (the second refused; its suggested --overwrite would have replaced the run). Each
// keeps its own history now, and both stay readable.
TEST(Enumerate, AfterARunOnTheSameConfigKeepsBothHistories) {
  TempFolder dir("enumerate-after-run");
  fs::copy_file(fs::path(COMBABC_SOURCE_DIR) / "examples/sensor-45cm/data.csv", dir / "data.csv");
  std::string text = Config("threshold = [0.5, 0.3]");
  Replace(text, "accepted_per_wave =", "accepted_per_wave = 20");
  std::ofstream(dir / "list.toml") << text;
  // Without -q each ends with the answer on stdout (issue 22, item 1): the clamps of both edges
  // side by side, clamp 1 and clamp 6 (5 per edge over 90 cm) on the first row, 0-18 cm.
  auto r = RunCli({"run", dir / "list.toml", "--no-report"}, dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("\nanswer: wave 2 of 2, paper estimator, 20 particles"), std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find(" edge 1 (y = 0)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\n     1  0-18  0."), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("      6  0-18  0."), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("most probable configurations"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(" simulations"), std::string::npos) << r.out;
  // A second run refuses to replace the history, and says how to (item 8).
  r = RunCli({"run", dir / "list.toml", "--no-report", "-q"}, dir.path());
  EXPECT_EQ(r.exit_code, kCantCreate) << r.err;
  EXPECT_NE(r.err.find("use --overwrite"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("-o DIR"), std::string::npos) << r.err;
  r = RunCli({"enumerate", dir / "list.toml", "--no-report"}, dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("history: " + dir / "out/enumeration/history.sqlite"), std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("\nanswer: exact (enumeration, "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(" P(fixed) exact (no Monte-Carlo error)"), std::string::npos) << r.out;
  for (const char* history : {"out/history.sqlite", "out/enumeration/history.sqlite"}) {
    SCOPED_TRACE(history);
    r = RunCli({"verify", dir / history}, dir.path());
    EXPECT_EQ(r.exit_code, 0) << r.err;
  }
  r = RunCli({"export", dir / "out/history.sqlite", "--no-netcdf"}, dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string summary = ReadFile(dir.path() / "out/export/summary.json");
  EXPECT_EQ(summary.find("\"termination\": \"enumerated\""), std::string::npos) << summary;
}

// Regression (issue 20, D15): more than 2^24 configurations were refused naming an internal
// struct ("SmcProblem::space"); the refusal names the config file, line and key that set the bits.
TEST(Enumerate, TooManyFreeBitsAreRefusedAtTheKeyThatSetsThem) {
  TempFolder dir("enumerate-too-many");
  fs::copy_file(fs::path(COMBABC_SOURCE_DIR) / "examples/sensor-45cm/data.csv", dir / "data.csv");
  std::string text = Config("threshold = [0.5, 0.3]");
  Replace(text, "per_edge =", "per_edge = 13");  // 26 clamps, 26 free bits
  std::ofstream(dir / "big.toml") << text;
  const int line = Lines(text.substr(0, text.find("per_edge = 13"))) + 1;
  const auto r = RunCli({"enumerate", dir / "big.toml", "--no-report", "-q"}, dir.path());
  EXPECT_EQ(r.exit_code, kConfig) << r.err;
  EXPECT_EQ(Lines(r.err), 1) << r.err;
  const std::string where = dir / "big.toml" + ":" + std::to_string(line) +
                            ": model.clamps.per_edge: gives 26 bits, 26 free after ties (2^26 ";
  EXPECT_NE(r.err.find(where), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("at most 2^24: tie bits ([sampler] tie"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("SmcProblem"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir.path() / "out"));
}

// Model choice through the CLI (docs/config.md, "Model choice"): two tiny sensors, clamped or
// simply supported clamps, 2^6 configurations each. `combabc run` writes each model's history
// and the model probabilities, which agree with `combabc enumerate`'s exact ones within 4
// Monte-Carlo errors; a second `run` reads the finished models instead of running them again.
double Column(const std::string& csv, const std::string& model, int column) {
  const auto at = csv.find("\n" + model + ",");
  EXPECT_NE(at, std::string::npos) << csv;
  std::string row = csv.substr(at + 1, csv.find('\n', at + 1) - at - 1);
  for (int c = 0; c < column; ++c) row = row.substr(row.find(',') + 1);
  return std::atof(row.c_str());
}

TEST(Enumerate, ModelChoiceRunAgreesWithTheExactModelProbabilities) {
  TempFolder dir("model-choice");
  WriteTinySensorData(dir.path());
  std::string config = TinySensorModelChoice("waves = 3\naccepted_per_wave = 200\nseed = 5\n",
                                             "4.0, 3.0, 2.4",
                                             "",
                                             "[output]\ndirectory = \"out\"\n\n");
  std::ofstream(dir / "run.toml") << config;
  auto r = RunCli({"run", dir / "run.toml", "--no-report", "-j", "1"}, dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // The model probabilities first, then each model's answer.
  const auto first = r.out.find("Model probabilities");
  ASSERT_NE(first, std::string::npos) << r.out;
  EXPECT_LT(first, r.out.find("answer:")) << r.out;
  EXPECT_NE(r.out.find("== model \"pinned\" =="), std::string::npos) << r.out;
  const std::string run = ReadFile(dir.path() / "out/model_choice/models.csv");
  ASSERT_TRUE(fs::exists(dir.path() / "out/models/pinned/history.sqlite"));
  ASSERT_TRUE(fs::exists(dir.path() / "out/model_choice/summary.json"));

  r = RunCli({"enumerate", dir / "run.toml", "--no-report", "-q"}, dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string exact = ReadFile(dir.path() / "out/enumeration/model_choice/models.csv");
  for (const std::string model : {"clamped", "pinned"}) {
    const double p = Column(run, model, 2);
    const double se = Column(run, model, 3);
    const double truth = Column(exact, model, 2);
    EXPECT_GT(truth, 0.05) << exact;  // both models fit some configurations
    EXPECT_GT(se, 0.0) << run;
    EXPECT_NEAR(p, truth, 4.0 * se) << model << "\n" << run << exact;
  }

  // Again: the finished models are read, not run (same numbers, no progress lines); with the
  // report on, the figure of the probabilities per wave is drawn.
  r = RunCli({"run", dir / "run.toml", "-j", "1"}, dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("wave 1:"), std::string::npos) << r.err;
  EXPECT_EQ(ReadFile(dir.path() / "out/model_choice/models.csv"), run);
  EXPECT_TRUE(fs::exists(dir.path() / "out/model_choice/model_probabilities.png")) << r.err;
  // waves.csv: one row per wave and model; its last wave is the table's estimate (both models
  // reached the final thresholds at their last wave).
  const std::string waves = ReadFile(dir.path() / "out/model_choice/waves.csv");
  for (const std::string model : {"clamped", "pinned"}) {
    EXPECT_NE(waves.find("\n3," + model + ","), std::string::npos) << waves;
    const std::string row = "\n" + waves.substr(waves.find("\n3," + model + ",") + 3);
    EXPECT_NEAR(Column(row, model, 3), Column(run, model, 2), 1e-9) << waves;
  }
  {
    // Without a python for the figure: a note, and the tables all the same.
    const ScopedEnv no_python("COMBABC_PYTHON", (dir.path() / "no-python").string());
    r = RunCli({"run", dir / "run.toml", "-j", "1"}, dir.path());
  }
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("note: the figure of the model probabilities per wave"), std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(dir.path() / "out/model_choice/model_probabilities.png"));
  EXPECT_EQ(ReadFile(dir.path() / "out/model_choice/waves.csv"), waves);

  // Any thread count gives the same models; a model stopped on its budget is resumed alone, and
  // the model choice run again then equals the uninterrupted one.
  r = RunCli({"run", dir / "run.toml", "--no-report", "-q", "-j", "2", "-o", dir / "j2"},
             dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(ReadFile(dir.path() / "j2/model_choice/models.csv"), run);
  std::string budget = config;
  budget.replace(budget.find("seed = 5"), 8, "seed = 5\nmax_simulations = 500");
  std::ofstream(dir / "budget.toml") << budget;
  r = RunCli({"run", dir / "budget.toml", "--no-report", "-q", "-j", "1", "-o", dir / "b"},
             dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const std::string model : {"clamped", "pinned"}) {
    const std::string history = dir / ("b/models/" + model + "/history.sqlite");
    r = RunCli({"resume", history, "--max-simulations", "0", "--no-report", "-q"}, dir.path());
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  r = RunCli({"run", dir / "budget.toml", "--no-report", "-q", "-j", "1", "-o", dir / "b"},
             dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(ReadFile(dir.path() / "b/model_choice/models.csv"), run);

  // An output folder that cannot be made: exit 73, not an internal error.
  std::ofstream(dir / "a-file") << "not a folder\n";
  r = RunCli({"run", dir / "run.toml", "--no-report", "-q", "-o", dir / "a-file"}, dir.path());
  EXPECT_EQ(r.exit_code, kCantCreate) << r.err;

  // Bad input: priors that do not sum to one.
  config.replace(config.find("prior = 0.6"), 11, "prior = 0.5");
  std::ofstream(dir / "bad.toml") << config;
  r = RunCli({"run", dir / "bad.toml", "--no-report"}, dir.path());
  EXPECT_EQ(r.exit_code, kConfig) << r.err;
  EXPECT_NE(r.err.find("model_choice.model[1].prior: the models' priors sum to 0.9"),
            std::string::npos)
      << r.err;
}

// method = "joint": one run over the model indicator and the clamps the two models share; the
// same exact probabilities (by enumerating each model) within 4 Monte-Carlo errors, each model's
// clamps given the model in bits.csv, and the same numbers for any thread count.
TEST(Enumerate, JointModelChoiceRunAgreesWithTheExactModelProbabilities) {
  TempFolder dir("joint-model-choice");
  WriteTinySensorData(dir.path());
  std::string config = TinySensorModelChoice("waves = 3\naccepted_per_wave = 300\nseed = 5\n",
                                             "4.0, 3.0, 2.4",
                                             "method = \"joint\"\n",
                                             "[output]\ndirectory = \"out\"\n\n");
  std::ofstream(dir / "run.toml") << config;
  auto r = RunCli({"run", dir / "run.toml", "--no-report", "-j", "1"}, dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("one joint run"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("== model \"pinned\" ==\nP(bit = 1 | model \"pinned\""), std::string::npos)
      << r.out;
  ASSERT_TRUE(fs::exists(dir.path() / "out/joint/history.sqlite"));
  const std::string run = ReadFile(dir.path() / "out/model_choice/models.csv");
  const std::string bits = ReadFile(dir.path() / "out/model_choice/bits.csv");
  EXPECT_NE(bits.find("\npinned,6,"), std::string::npos) << bits;
  r = RunCli({"enumerate", dir / "run.toml", "--no-report", "-q"}, dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string exact = ReadFile(dir.path() / "out/enumeration/model_choice/models.csv");
  for (const std::string model : {"clamped", "pinned"}) {
    const double p = Column(run, model, 2);
    const double se = Column(run, model, 3);
    EXPECT_GT(se, 0.0) << run;
    EXPECT_NEAR(p, Column(exact, model, 2), 4.0 * se) << model << "\n" << run << exact;
  }
  r = RunCli({"run", dir / "run.toml", "--no-report", "-q", "-j", "2", "-o", dir / "j2"},
             dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(ReadFile(dir.path() / "j2/model_choice/models.csv"), run);
  // An unknown method is refused at its key.
  config.replace(config.find("method = \"joint\""), 16, "method = \"jump\"");
  std::ofstream(dir / "bad.toml") << config;
  r = RunCli({"run", dir / "bad.toml", "--no-report"}, dir.path());
  EXPECT_EQ(r.exit_code, kConfig) << r.err;
  EXPECT_NE(r.err.find("model_choice.method: unknown method 'jump'"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace combabc::testing
