// Every shipped example config (examples/*/*.toml), run as shipped (its seed), must never be
// confidently wrong: no clamp may end with |P(fixed) - 0.5| > 0.4 on the wrong side of the ground
// truth its data were generated from. The truth is read from the data file's header, which
// examples/generate_data.py writes ("# truth <one 0/1 per clamp> ..."), so it is stated once.
// And no example may draw a warning from the fit and sanity checks. An example too slow to run as
// shipped has a reduced test of its own instead, and the CalculiX one is run as shipped by its own
// test, through the CLI, with these checks (OwnTest). A model-choice config (examples/
// sensor-model-choice) has these checks on each model's run, and must give the model named by the
// data's header ("# truth ... support <model>") P >= 0.95.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "combabc/config/config.hpp"
#include "combabc/data/measured_data.hpp"
#include "combabc/export/fit_checks.hpp"
#include "combabc/services/model_choice_run.hpp"
#include "combabc/services/run.hpp"
#include "examples/calculix_support.hpp"
#include "support/test_support.hpp"

namespace combabc::testing {
namespace {

namespace fs = std::filesystem;

// A clamp is "confidently" placed when its marginal is this far from the prior's 0.5.
constexpr double kConfident = 0.4;

// Examples whose simulator runs an external program that scripts/setup.sh installs; without it
// on PATH (a machine set up otherwise) the example is skipped, saying so.
std::string MissingProgram(const std::string& example) {
  if (example != "sensor-calculix") return {};
  return ProgramOnPath("ccx") ? "" : "ccx";
}

// Examples run by a test of their own, named here, and why: the custom simulator's command is
// the worker's model, and a test checks that it gives the worker's history; sensor-multifidelity
// is too slow to run as shipped (about 1,300 CalculiX runs alone, 491-636 multi-fidelity) and runs
// reduced; sensor-calculix runs as shipped there (86 CalculiX runs, about 49 s of CPU: not twice).
std::string OwnTest(const std::string& example, const std::string& config) {
  if (example == "custom-simulator" && config == "command.toml") {
    return "worker.toml's model as a program per simulation, its history the worker's "
           "(tests/e2e/external_simulator_test.cpp; 397 python3 processes as shipped)";
  }
  if (example == "sensor-multifidelity") {
    return "too slow as shipped; tests/examples/sensor_multifidelity_test.cpp runs it reduced";
  }
  if (example == "sensor-calculix") {
    return "tests/examples/sensor_calculix_test.cpp runs it as shipped, with these checks";
  }
  return {};
}

std::vector<fs::path> ExampleConfigs() {
  std::vector<fs::path> configs;
  for (const auto& dir : fs::directory_iterator(fs::path(COMBABC_SOURCE_DIR) / "examples")) {
    if (!dir.is_directory()) continue;
    for (const auto& file : fs::directory_iterator(dir.path())) {
      if (file.path().extension() == ".toml") configs.push_back(file.path());
    }
  }
  std::sort(configs.begin(), configs.end());
  return configs;
}

// The "# truth 0110..." header line generate_data.py writes; empty if there is none.
std::string TruthOf(const std::string& csv) {
  std::ifstream in(csv);
  std::string line;
  while (std::getline(in, line) && line.rfind('#', 0) == 0) {
    std::istringstream words(line);
    std::string hash, key, bits;
    words >> hash >> key >> bits;
    if (key == "truth") return bits;
  }
  return {};
}

// The word after `key` in the data file's header lines ("# truth 0110... support clamped ...").
std::string HeaderWord(const std::string& csv, const std::string& key) {
  std::ifstream in(csv);
  std::string line;
  while (std::getline(in, line) && line.rfind('#', 0) == 0) {
    std::istringstream words(line);
    std::string word;
    while (words >> word) {
      if (word == key && words >> word) return word;
    }
  }
  return {};
}

std::string List(const std::vector<int>& clamps) {
  if (clamps.empty()) return "none";
  std::string out;
  for (int c : clamps) out += (out.empty() ? "" : ", ") + std::to_string(c);
  return out;
}

// A run's posterior against the truth: no clamp confidently wrong, at least two recovered, and
// with `fit_checks` no warning from the fit and sanity checks (a model choice's losing model may
// well fit badly: that is why it loses).
void CheckRun(const std::string& name,
              const std::string& truth,
              Estimator estimator,
              const services::RunOutcome& outcome,
              bool fit_checks = true) {
  ASSERT_FALSE(outcome.history.waves.empty());
  const auto& marginals = outcome.history.waves.back().marginals(estimator);
  ASSERT_EQ(marginals.size(), truth.size());

  std::vector<int> recovered, wrong;
  for (std::size_t k = 0; k < truth.size(); ++k) {
    if (std::abs(marginals[k] - 0.5) <= kConfident) continue;
    const bool says_fixed = marginals[k] > 0.5;
    (says_fixed == (truth[k] == '1') ? recovered : wrong).push_back(static_cast<int>(k) + 1);
  }
  std::cout << name << ": recovered clamps " << List(recovered) << "; confidently wrong "
            << List(wrong) << " (" << outcome.history.summary.simulations << " simulations)\n";
  EXPECT_TRUE(wrong.empty()) << "confidently wrong about clamps " << List(wrong);
  // And not merely uninformative: each example identifies the clamps next to its load.
  EXPECT_GE(recovered.size(), 2u) << "recovered only " << List(recovered);
  // Nor do the fit and sanity checks (docs/history.md, "Checks") find fault with an example.
  const std::string checks = FormatFitChecks(outcome.checks, "m");
  std::cout << checks;
  if (!fit_checks) return;
  for (const auto* list : {&outcome.checks.before, &outcome.checks.after}) {
    for (const CheckMessage& m : *list) {
      EXPECT_NE(m.severity, "warning") << m.code << ": " << m.message;
    }
  }
}

TEST(ExamplePosteriors, NoExampleIsConfidentlyWrongAboutItsGroundTruth) {
  const auto configs = ExampleConfigs();
  ASSERT_GE(configs.size(), 4u) << "examples/*/*.toml not found";
  const TempFolder scratch("example-posteriors");
  for (const fs::path& path : configs) {
    const std::string name =
        path.parent_path().filename().string() + "/" + path.filename().string();
    SCOPED_TRACE(name);
    if (const std::string own =
            OwnTest(path.parent_path().filename().string(), path.filename().string());
        !own.empty()) {
      std::cout << name << ": skipped, " << own << "\n";
      continue;
    }
    if (const std::string missing = MissingProgram(path.parent_path().filename().string());
        !missing.empty()) {
      std::cout << name << ": skipped, " << missing << " is not on PATH (scripts/setup.sh)\n";
      continue;
    }
    const CalibrationConfig config = LoadConfig(path.string());
    const std::string truth =
        TruthOf(ResolvePath(config.directory, config.experiments[0].data.csv));
    ASSERT_EQ(static_cast<int>(truth.size()), config.space.dimension)
        << "no '# truth' header with one bit per clamp in " << config.experiments[0].data.csv;

    services::RunRequest request;
    request.config_path = path.string();
    request.output_directory = scratch / name;
    request.threads = 2;
    request.report = false;
    if (services::HasModelChoice(path.string())) {
      const std::string support =
          HeaderWord(ResolvePath(config.directory, config.experiments[0].data.csv), "support");
      services::ModelChoiceOutcome choice;
      try {
        choice = services::RunModelChoice(request);
      } catch (const std::exception& e) {
        ADD_FAILURE() << e.what();
        continue;
      }
      bool found = false;
      for (std::size_t k = 0; k < choice.models.size(); ++k) {
        const bool true_model = choice.models[k].name == support;
        CheckRun(name + " (" + choice.models[k].name + ")",
                 truth,
                 config.smc.estimator,
                 choice.runs[k],
                 true_model);
        if (!true_model) continue;
        found = true;
        EXPECT_GE(choice.models[k].probability, 0.95) << "the true model " << support;
      }
      EXPECT_TRUE(found) << "no model named '" << support << "' (the data's '# ... support')";
      continue;
    }
    services::RunOutcome outcome;
    try {
      outcome = services::RunCalibration(request);
    } catch (const std::exception& e) {  // e.g. a config error: report it, go on with the others
      ADD_FAILURE() << e.what();
      continue;
    }
    CheckRun(name, truth, config.smc.estimator, outcome);
  }
}

}  // namespace
}  // namespace combabc::testing
