// Noise-aware acceptance on the sensor (Wilkinson 2013) against the failure it exists for: data
// from a different, finer model (mesh x 2, foundation stiffness +20 %) plus 1 % Gaussian noise.
// With the gaussian noise model (sigma estimated from the data) no clamp may end confidently
// wrong (|P - 0.5| > 0.4 on the wrong side of the truth).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "combabc/config/config.hpp"
#include "combabc/plate/sensor_model.hpp"
#include "combabc/rng/random_stream.hpp"
#include "combabc/services/run.hpp"

namespace combabc::testing {
namespace {

namespace fs = std::filesystem;

constexpr double kConfident = 0.4;
const std::string kTruth = "010110100101011001101001011010011010";

// The model sections of the shipped 70 cm example (everything before [data]).
std::string ModelSections() {
  std::ifstream in(fs::path(COMBABC_SOURCE_DIR) / "examples/sensor-70cm/least_squares.toml");
  std::stringstream text;
  text << in.rdbuf();
  const std::string s = text.str();
  return s.substr(0, s.find("[data]"));
}

std::string Config(const std::string& metric, int waves) {
  return ModelSections() +
         "[data]\ncsv = \"data.csv\"\nposition_column = \"position_cm\"\n"
         "displacement_column = \"w\"\nposition_unit = \"cm\"\ndisplacement_unit = \"um\"\n"
         "normalise = true\n\n" +
         metric + "\n[sampler]\nwaves = " + std::to_string(waves) +
         "\naccepted_per_wave = 500\nestimator = \"importance\"\n"
         "seed = 2013\nthreads = 2\n\n[output]\ndirectory = \"results\"\n";
}

// The truth's profile from the finer, perturbed model, 1 % noise (of the peak), every 1 cm.
void WriteData(const CalibrationConfig& base, const fs::path& csv) {
  plate::SensorOptions o = base.model;
  o.elements_per_section *= 2;
  o.elements_across_width = 2 * o.ElementsAcrossWidth();
  o.foundation_stiffness *= 1.2;
  o.normalise = true;
  o.load_cases[0].output_positions.clear();
  for (int cm = 30; cm <= 89; ++cm) o.load_cases[0].output_positions.push_back(cm * 0.01);
  const plate::SensorModel model(o);
  std::vector<std::uint8_t> clamps;
  for (char c : kTruth) clamps.push_back(c == '1');
  std::vector<double> w(o.load_cases[0].output_positions.size());
  model.Profile(clamps, w);
  RandomStream rng(7, 0, 0);
  std::ofstream out(csv);
  out << "position_cm,w\n";
  for (std::size_t i = 0; i < w.size(); ++i) {
    out << 30 + static_cast<int>(i) << ',' << w[i] + 0.01 * rng.Normal() << '\n';
  }
}

std::vector<int> ConfidentlyWrong(const fs::path& dir, const std::string& metric, int waves) {
  fs::create_directories(dir);
  { std::ofstream(dir / "run.toml") << Config(metric, waves); }
  WriteData(LoadConfig((dir / "run.toml").string()), dir / "data.csv");
  services::RunRequest request;
  request.config_path = (dir / "run.toml").string();
  request.report = false;
  const auto outcome = services::RunCalibration(request);
  const auto& last = outcome.history.waves.back();
  std::vector<int> wrong;
  std::cout << "waves " << outcome.history.waves.size() << ", "
            << outcome.history.summary.simulations << " simulations, last eps/T";
  for (double e : last.thresholds) std::cout << ' ' << e;
  std::cout << ", ESS " << last.ess << "\nP(fixed):";
  for (std::size_t k = 0; k < kTruth.size(); ++k) {
    const double p = last.marginals_importance[k];
    std::cout << ' ' << std::round(p * 100) / 100;
    if (std::abs(p - 0.5) > kConfident && (p > 0.5) != (kTruth[k] == '1')) {
      wrong.push_back(static_cast<int>(k) + 1);
    }
  }
  std::cout << "\nconfidently wrong: " << wrong.size() << " clamps\n";
  return wrong;
}

TEST(NoiseAwareSensor, GaussianNoiseModelIsNotConfidentlyWrong) {
  const fs::path scratch =
      fs::temp_directory_path() / ("combabc-noise-aware-" + std::to_string(::getpid()));
  const auto wrong = ConfidentlyWrong(scratch / "gaussian",
                                      "[metric]\nquantile = 0.3\nnoise = \"gaussian\"\n"
                                      "sigma_noise = \"estimate\"\n\n[[metric.component]]\n"
                                      "type = \"least_squares\"\nwindow = [30, 89]\n",
                                      30);
  EXPECT_TRUE(wrong.empty()) << wrong.size() << " clamps confidently wrong";
  // The plain least-squares threshold on the same data (10 waves) left clamps confidently wrong
  // (docs/algorithm.md); it asserted nothing here, so it is no longer run (CI time).
  fs::remove_all(scratch);
}

}  // namespace
}  // namespace combabc::testing
