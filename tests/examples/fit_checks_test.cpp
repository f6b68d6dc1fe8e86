// The fit and sanity checks on the 45 cm example, in short runs (3 waves of 100): the two
// unit mistakes (`length = 90`, cm typed for m; `normalise = false` with the data in µm and the
// unit left at m), a zero load and signed data warn, naming the key; the example as shipped does
// not. (The shipped examples at full length: tests/examples/posterior_test.cpp.) And the issue's
// overconfident case: a full-length scan calibrated with plain thresholds for 8 waves warns of
// the threshold below the noise; the noise-aware acceptance on the same data does not.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "combabc/config/config.hpp"
#include "combabc/export/fit_checks.hpp"
#include "combabc/plate/sensor_model.hpp"
#include "combabc/rng/random_stream.hpp"
#include "combabc/services/run.hpp"
#include "support/test_support.hpp"

namespace combabc::testing {
namespace {

namespace fs = std::filesystem;

const fs::path kExample = fs::path(COMBABC_SOURCE_DIR) / "examples" / "sensor-45cm";

std::string ExampleText() {
  std::ifstream in(kExample / "least_squares.toml");
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

void Replace(std::string& text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  ASSERT_NE(at, std::string::npos) << from;
  text.replace(at, from.size(), to);
}

// The example's config with `edit` applied, short waves, its data at `csv`; run, checks returned.
FitChecks Checks(const TempFolder& scratch,
                 const std::string& name,
                 const std::function<void(std::string&)>& edit,
                 const fs::path& csv = kExample / "data.csv") {
  std::string text = ExampleText();
  Replace(text, "csv = \"data.csv\"", "csv = \"" + csv.string() + "\"");
  Replace(text, "waves = 5", "waves = 3");
  Replace(text, "accepted_per_wave = 500", "accepted_per_wave = 100");
  edit(text);
  const fs::path dir = scratch.path() / name;
  fs::create_directories(dir);
  { std::ofstream(dir / "run.toml") << text; }
  services::RunRequest request;
  request.config_path = (dir / "run.toml").string();
  request.threads = 2;
  request.report = false;
  const services::RunOutcome outcome = services::RunCalibration(request);
  std::cout << name << ":\n" << FormatFitChecks(outcome.checks, "m");
  return outcome.checks;
}

std::vector<std::string> Warnings(const FitChecks& checks) {
  std::vector<std::string> codes;
  for (const auto* list : {&checks.before, &checks.after}) {
    for (const CheckMessage& m : *list) {
      if (m.severity == "warning") codes.push_back(m.code);
    }
  }
  return codes;
}

bool Mentions(const FitChecks& checks, const std::string& code, const std::string& key) {
  for (const auto* list : {&checks.before, &checks.after}) {
    for (const CheckMessage& m : *list) {
      if (m.code == code && m.message.find(key) != std::string::npos) return true;
    }
  }
  return false;
}

TEST(FitChecksOnTheExample, AsShippedNothingWarns) {
  const TempFolder scratch("fit-checks-shipped");
  const FitChecks checks = Checks(scratch, "shipped", [](std::string&) {});
  EXPECT_TRUE(Warnings(checks).empty()) << FormatFitChecks(checks, "m");
  ASSERT_EQ(checks.fit.size(), 1u);
  EXPECT_EQ(checks.fit[0].verdict, "good");
  ASSERT_EQ(checks.predictive.size(), 1u);
  EXPECT_EQ(checks.predictive[0].positions.size(), 33u);
}

TEST(FitChecksOnTheExample, LengthInCentimetresWarns) {
  const TempFolder scratch("fit-checks-length");
  const FitChecks checks = Checks(scratch, "length = 90", [](std::string& text) {
    Replace(text, "length = 0.90", "length = 90");
  });
  EXPECT_FALSE(Warnings(checks).empty());
  EXPECT_TRUE(Mentions(checks, "poor_fit", "[model] length")) << FormatFitChecks(checks, "m");
}

TEST(FitChecksOnTheExample, MicrometresReadAsMetresWarn) {
  const TempFolder scratch("fit-checks-units");
  const FitChecks checks = Checks(scratch, "normalise = false, um as m", [](std::string& text) {
    Replace(text, "displacement_unit = \"um\"", "displacement_unit = \"m\"");
    Replace(text, "normalise = true ", "normalise = false");
  });
  EXPECT_TRUE(Mentions(checks, "units_mismatch", "displacement_unit"))
      << FormatFitChecks(checks, "m");
}

TEST(FitChecksOnTheExample, ZeroLoadWarns) {
  const TempFolder scratch("fit-checks-zero-load");
  FitChecks checks;
  try {
    checks = Checks(scratch, "amplitude = 0", [](std::string& text) {
      Replace(text, "amplitude = 0.042", "amplitude = 0.0");
      Replace(text, "waves = 3", "waves = 1");
    });
  } catch (const std::exception& e) {
    // A config error that names the amplitude is a clear answer too.
    EXPECT_NE(std::string(e.what()).find("amplitude"), std::string::npos) << e.what();
    return;
  }
  const auto codes = Warnings(checks);
  EXPECT_TRUE(std::find(codes.begin(), codes.end(), "zero_outputs") != codes.end() ||
              std::find(codes.begin(), codes.end(), "nothing_accepted") != codes.end())
      << FormatFitChecks(checks, "m");
}

TEST(FitChecksOnTheExample, SignedDataWarn) {
  const TempFolder scratch("fit-checks-signed");
  // The example's data with every other point's sign flipped (signed displacements).
  std::ifstream in(kExample / "data.csv");
  std::ofstream out(scratch / "signed.csv");
  int row = 0;
  for (std::string line; std::getline(in, line);) {
    if (!line.empty() && line[0] != '#' && line.find(',') != std::string::npos &&
        std::isdigit(static_cast<unsigned char>(line[0])) && ++row % 2 == 0) {
      line.insert(line.find(',') + 1, "-");
    }
    out << line << '\n';
  }
  out.close();
  const FitChecks checks = Checks(
      scratch, "signed data", [](std::string&) {}, scratch.path() / "signed.csv");
  EXPECT_TRUE(Mentions(checks, "negative_data", "displacement_column"))
      << FormatFitChecks(checks, "m");
}

// The 45 cm example's truth, scanned 0-89 cm, from a finer mesh with a 20 % stiffer foundation,
// normalised, plus noise of 1 % of the peak; written as position_cm,w.
void WriteFullLengthScan(const fs::path& csv) {
  const CalibrationConfig base = LoadConfig((kExample / "least_squares.toml").string());
  plate::SensorOptions o = base.model;
  o.elements_per_section *= 2;
  o.elements_across_width = 2 * o.ElementsAcrossWidth();
  o.foundation_stiffness *= 1.2;
  o.normalise = true;
  o.load_cases.resize(1);
  o.load_cases[0].output_positions.clear();
  for (int cm = 0; cm <= 89; ++cm) o.load_cases[0].output_positions.push_back(cm * 0.01);
  const plate::SensorModel model(o);
  const std::string truth = "101101010001101001011011010001101100";  // examples/sensor-45cm
  std::vector<std::uint8_t> clamps;
  clamps.reserve(truth.size());
  for (char c : truth) clamps.push_back(c == '1');
  std::vector<double> w(o.load_cases[0].output_positions.size());
  model.Profile(clamps, w);
  RandomStream rng(7, 0, 0);
  std::ofstream out(csv);
  out << "position_cm,w\n";
  for (std::size_t i = 0; i < w.size(); ++i) out << i << ',' << w[i] + 0.01 * rng.Normal() << '\n';
}

FitChecks FullLengthChecks(const TempFolder& scratch,
                           const std::string& name,
                           const std::string& metric,
                           int waves) {
  std::string text = ExampleText();
  text = text.substr(0, text.find("[data]"));
  text += "[data]\ncsv = \"" + (scratch.path() / "scan.csv").string() +
          "\"\nposition_column = \"position_cm\"\ndisplacement_column = \"w\"\n"
          "position_unit = \"cm\"\ndisplacement_unit = \"um\"\nnormalise = true\n\n" +
          metric + "\n[[metric.component]]\ntype = \"least_squares\"\nwindow = [0, 89]\n\n" +
          "[sampler]\nwaves = " + std::to_string(waves) +
          "\naccepted_per_wave = 500\nestimator = \"importance\"\nseed = 2024\nthreads = 2\n";
  const fs::path dir = scratch.path() / name;
  fs::create_directories(dir);
  { std::ofstream(dir / "run.toml") << text; }
  services::RunRequest request;
  request.config_path = (dir / "run.toml").string();
  request.report = false;
  const services::RunOutcome outcome = services::RunCalibration(request);
  std::cout << name << ":\n" << FormatFitChecks(outcome.checks, "m");
  return outcome.checks;
}

TEST(FitChecksOnTheExample, FullLengthScanWithPlainThresholdsWarnsOfOverconfidence) {
  const TempFolder scratch("fit-checks-full-length");
  WriteFullLengthScan(scratch.path() / "scan.csv");
  const FitChecks plain = FullLengthChecks(scratch, "plain", "[metric]\nquantile = 0.3\n", 8);
  EXPECT_TRUE(Mentions(plain, "threshold_below_noise", "noise = \"gaussian\""))
      << FormatFitChecks(plain, "m");
  const FitChecks aware = FullLengthChecks(
      scratch, "noise-aware", "[metric]\nquantile = 0.3\nnoise = \"gaussian\"\ntarget = 1\n", 30);
  EXPECT_TRUE(Warnings(aware).empty()) << FormatFitChecks(aware, "m");
}

}  // namespace
}  // namespace combabc::testing
