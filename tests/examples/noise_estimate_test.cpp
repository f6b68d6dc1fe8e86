// The noise estimate behind `sigma_noise = "estimate"` and the fit checks (EstimateNoiseSigma,
// docs/algorithm.md "Noise estimate") on the shipped examples' profile shapes: the ground truth
// of each example simulated by the built-in sensor at the measured positions, normalised as the
// data are, plus Gaussian noise of a known sigma. It must recover sigma (the mean over 20 seeds
// within 25 %) and read little on the noise-free profile, whose steep start and clamp kinks the
// former second-difference estimate took for noise (0.10 on the 70 cm shape).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "combabc/config/config.hpp"
#include "combabc/config/distance_from_config.hpp"
#include "combabc/metrics/composite_distance.hpp"
#include "combabc/plate/sensor_model.hpp"
#include "combabc/rng/random_stream.hpp"

namespace combabc::testing {
namespace {

namespace fs = std::filesystem;

// The "# truth 0110..." header line examples/generate_data.py writes.
std::string TruthOf(const fs::path& csv) {
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

struct Shape {
  std::vector<double> x;
  std::vector<double> y;  // noise-free, peak 1 over x
};

// The example's ground truth simulated at `positions` (its measured ones when empty) by the
// config's own model, normalised over them.
Shape TruthShape(const std::string& example,
                 const std::string& config_file,
                 std::vector<double> positions = {}) {
  const fs::path dir = fs::path(COMBABC_SOURCE_DIR) / "examples" / example;
  const CalibrationConfig config = LoadConfig((dir / config_file).string());
  if (positions.empty()) positions = LoadExperimentData(config)[0].positions;
  const std::string truth = TruthOf(dir / "data.csv");
  EXPECT_EQ(static_cast<int>(truth.size()), config.space.dimension);
  plate::SensorOptions o = config.model;
  o.normalise = true;
  o.load_cases.resize(1);
  o.load_cases[0].output_positions = positions;
  const plate::SensorModel model(o);
  std::vector<std::uint8_t> clamps;
  for (char c : truth) clamps.push_back(c == '1');
  Shape s;
  s.x = positions;
  s.y.resize(positions.size());
  model.Profile(clamps, s.y);
  return s;
}

// The former estimator (second differences, Gasser et al. 1986), for the record.
double SecondDifferences(const Shape& s) {
  double sum = 0.0;
  for (std::size_t i = 1; i + 1 < s.x.size(); ++i) {
    const double a = (s.x[i + 1] - s.x[i]) / (s.x[i + 1] - s.x[i - 1]);
    const double b = (s.x[i] - s.x[i - 1]) / (s.x[i + 1] - s.x[i - 1]);
    const double e = a * s.y[i - 1] + b * s.y[i + 1] - s.y[i];
    sum += e * e / (a * a + b * b + 1.0);
  }
  return std::sqrt(sum / static_cast<double>(s.x.size() - 2));
}

// `clean_below`: the most the noise-free profile may read; `sigmas`: the noise levels recovered.
void ExpectRecoversKnownSigmas(const std::string& name,
                               const Shape& s,
                               double clean_below,
                               const std::vector<double>& sigmas) {
  SCOPED_TRACE(name);
  const double clean = EstimateNoiseSigma(s.x, s.y);
  std::cout << name << " (" << s.x.size() << " points): noise-free estimate " << clean
            << " (second differences: " << SecondDifferences(s) << ")\n";
  // Small against the 1 % noise of the examples' data.
  EXPECT_LT(clean, clean_below);
  constexpr int kSeeds = 20;
  for (double sigma : sigmas) {
    double sum = 0.0;
    double lowest = 1e300;
    double highest = 0.0;
    for (int seed = 0; seed < kSeeds; ++seed) {
      RandomStream rng(2026, 0, static_cast<std::uint64_t>(seed));
      std::vector<double> y = s.y;
      for (double& v : y) v += sigma * rng.Normal();
      const double estimate = EstimateNoiseSigma(s.x, y);
      sum += estimate;
      lowest = std::min(lowest, estimate);
      highest = std::max(highest, estimate);
    }
    const double mean = sum / kSeeds;
    std::cout << "  sigma " << sigma << ": mean estimate " << mean << " (" << lowest << " to "
              << highest << " over " << kSeeds << " seeds)\n";
    EXPECT_NEAR(mean / sigma, 1.0, 0.25) << "sigma " << sigma;
    // No single data set is read as noise-free or as ten times its noise.
    EXPECT_GT(lowest, 0.3 * sigma);
    EXPECT_LT(highest, 3.0 * sigma);
  }
}

TEST(NoiseEstimate, RecoversKnownSigmaOnThe45cmExampleShape) {
  ExpectRecoversKnownSigmas("45 cm, 48-80 cm",
                            TruthShape("sensor-45cm", "least_squares.toml"),
                            0.001,
                            {0.003, 0.01, 0.03});
}

TEST(NoiseEstimate, RecoversKnownSigmaOnThe70cmExampleShape) {
  // 16 points over which the profile falls from 0.9 to 0.01 of its peak, past a clamp's kink: the
  // profile itself reads 0.0025, so a noise well below 1 % is overestimated (0.003 reads 0.004);
  // the examples' 1 % and more are recovered.
  ExpectRecoversKnownSigmas("70 cm, 74-89 cm",
                            TruthShape("sensor-70cm", "split_least_squares.toml"),
                            0.004,
                            {0.01, 0.03});
}

TEST(NoiseEstimate, RecoversKnownSigmaOnAFullLengthScanThroughTheLoad) {
  // The design example's experiments: the 45 cm load, scanned 0-89 cm, peak and kinks included.
  std::vector<double> x;
  for (int cm = 0; cm <= 89; ++cm) x.push_back(cm * 0.01);
  ExpectRecoversKnownSigmas("45 cm, 0-89 cm",
                            TruthShape("sensor-45cm", "least_squares.toml", x),
                            0.001,
                            {0.003, 0.01, 0.03});
}

// Issue 33: the design example's data are amplitudes |w + e| of full-length scans (0-90 cm), most
// of whose points lie at the noise floor, where |e| has the spread 0.60 sigma: the Gaussian
// estimate read 0.63-0.74 of sigma on them. The noise-free scans of the study's sensor (the finer
// perturbed model, examples/sensor-design/truth_profiles.csv) with the study's noise, sigma 1 %
// of the peak, then normalised to peak 1 as [data] normalise does, 20 seeds each: the amplitude
// estimate (noise = "folded_normal") must recover sigma within 10 % on average on every scan; the
// Gaussian one stays low. Prints the table of docs/algorithm.md, "Noise estimate".
TEST(NoiseEstimate, AmplitudeEstimateRecoversSigmaOnTheDesignStudysScans) {
  std::ifstream in(fs::path(COMBABC_SOURCE_DIR) / "examples" / "sensor-design" /
                   "truth_profiles.csv");
  ASSERT_TRUE(in) << "examples/sensor-design/truth_profiles.csv";
  std::vector<std::string> names;
  std::vector<Shape> scans;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line.rfind("experiment,", 0) == 0) continue;
    std::istringstream row(line);
    std::string name, cm, um;
    std::getline(row, name, ',');
    std::getline(row, cm, ',');
    std::getline(row, um, ',');
    if (names.empty() || names.back() != name) {
      names.push_back(name);
      scans.emplace_back();
    }
    scans.back().x.push_back(std::stod(cm) * 0.01);
    scans.back().y.push_back(std::stod(um));
  }
  ASSERT_EQ(scans.size(), 13u);
  constexpr int kSeeds = 20;
  std::cout << "| scan | Gaussian estimate / sigma | amplitude estimate / sigma | floor points | "
               "degrees of freedom |\n";
  for (std::size_t k = 0; k < scans.size(); ++k) {
    SCOPED_TRACE(names[k]);
    const Shape& s = scans[k];
    ASSERT_EQ(s.x.size(), 91u);
    const double peak = *std::max_element(s.y.begin(), s.y.end());
    double amplitude = 0.0;
    double gaussian = 0.0;
    double lowest = 1e300;
    double highest = 0.0;
    double floor = 0.0;
    double dof = 0.0;
    for (int seed = 0; seed < kSeeds; ++seed) {
      RandomStream rng(2033, k, static_cast<std::uint64_t>(seed));
      std::vector<double> y = s.y;
      for (double& v : y) v = std::abs(v + 0.01 * peak * rng.Normal());
      const double top = *std::max_element(y.begin(), y.end());
      for (double& v : y) v /= top;
      const double sigma = 0.01 * peak / top;  // in the normalised units
      const AmplitudeNoiseEstimate a = EstimateAmplitudeNoise(s.x, y);
      amplitude += a.sigma / sigma / kSeeds;
      lowest = std::min(lowest, a.sigma / sigma);
      highest = std::max(highest, a.sigma / sigma);
      floor += static_cast<double>(a.floor_points) / kSeeds;
      dof += a.dof / kSeeds;
      gaussian += EstimateNoiseSigma(s.x, y) / sigma / kSeeds;
    }
    std::printf("| %s | %.2f | %.2f (%.2f-%.2f) | %.0f | %.0f |\n",
                names[k].c_str(),
                gaussian,
                amplitude,
                lowest,
                highest,
                floor,
                dof);
    EXPECT_NEAR(amplitude, 1.0, 0.1);
    EXPECT_LT(gaussian, 0.8);
  }
}

}  // namespace
}  // namespace combabc::testing
