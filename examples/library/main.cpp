// combabc as a library, with the engine alone (README, "As a library"): which of a beam's six
// supports are fixed, from its deflection measured near the left end only. Combinatorial ABC-SMC
// estimates the posterior; exact enumeration of the 2^6 configurations gives it exactly, and the
// program fails unless the estimate agrees within 5 Monte-Carlo standard errors.
//
// By hand: the data see supports 1-3 (fixed, free, fixed) and not 4-6, whose bumps stay below the
// threshold there, so the exact posterior of supports 1-3 is 1, 0, 1 and that of supports 4-6 is
// their prior, 0.3, 0.5, 0.7. ctest -L packaging builds this file against the installed package
// and checks that it prints these numbers.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <span>
#include <utility>
#include <vector>

#include "combabc/samplers/combinatorial_smc.hpp"
#include "combabc/samplers/enumeration.hpp"

namespace {

constexpr int kSupports = 6;
constexpr int kPoints = 7;  // deflection measured at x = 0, 0.03, ..., 0.18 m

// The model: a support that is not fixed (bit 0) lets the beam sag by a bump around it, as the
// README's external worker does. Deterministic, so it ignores its random stream; thread-safe.
class Beam : public combabc::Simulator {
 public:
  int output_size() const override { return kPoints; }
  void Simulate(const combabc::ParameterView& theta,
                combabc::RandomStream& /*rng*/,
                std::span<double> out) const override {
    for (int j = 0; j < kPoints; ++j) {
      const double x = 0.03 * j;
      out[j] = 0.05;
      for (int k = 0; k < kSupports; ++k) {
        const double centre = 0.05 + 0.1 * k;
        if (theta.bits[k] == 0) out[j] += std::exp(-std::pow((x - centre) / 0.06, 2));
      }
    }
  }
};

// One threshold component: the largest deviation from the measured deflection.
class MaxDeviation : public combabc::Distance {
 public:
  explicit MaxDeviation(std::vector<double> measured) : measured_(std::move(measured)) {}
  std::vector<combabc::DistanceComponent> components() const override { return {{"max_dev"}}; }
  void Evaluate(std::span<const double> simulated, std::span<double> out) const override {
    out[0] = 0.0;
    for (int j = 0; j < kPoints; ++j) {
      out[0] = std::max(out[0], std::abs(simulated[j] - measured_[j]));
    }
  }

 private:
  std::vector<double> measured_;
};

}  // namespace

int main() {
  combabc::BinarySpaceOptions prior;  // P(support fixed), one per support
  prior.dimension = kSupports;
  prior.prior_one = {0.5, 0.5, 0.5, 0.3, 0.5, 0.7};
  const combabc::ParameterSpace space{combabc::BinarySpace(prior)};
  Beam simulator;
  // The "measurement": the model with supports 1, 3, 4 and 6 fixed.
  const combabc::ParameterValue truth{{1, 0, 1, 1, 0, 1}, {}};
  std::vector<double> measured(kPoints);
  combabc::RandomStream unused(0, 0, 0);
  simulator.Simulate(truth.view(), unused, measured);
  const MaxDeviation distance(measured);
  const double final_threshold = 0.05;

  combabc::SmcOptions options;  // every field documented, checked by IsValid()
  options.num_waves = 4;
  options.accepted_per_wave = 1000;
  options.estimator = combabc::Estimator::kImportance;
  options.thresholds = {{combabc::ThresholdKind::kList, {1.0, 0.5, 0.2, final_threshold}}};
  options.seed = 1;
  const combabc::RunHistory history =
      combabc::RunCombinatorialSmc({&space, &simulator, &distance}, options);
  std::cout << history.FullReport(options.estimator);
  const combabc::WaveRecord& last = history.waves.back();
  const std::vector<double>& estimate = last.marginals(options.estimator);

  combabc::EnumerationOptions exact_options;
  exact_options.thresholds = {final_threshold};
  const combabc::EnumerationResult exact =
      combabc::Enumerate({&space, &simulator, &distance}, exact_options);

  bool agree = last.thresholds[0] == final_threshold;
  std::printf("support  prior  exact   ABC-SMC  bound\n");
  for (int k = 0; k < kSupports; ++k) {
    const double p = exact.marginals[k];
    // 5 binomial standard errors at the final wave's effective sample size, and a floor for an
    // exact 0 or 1, whose standard error is 0.
    const double bound = 5.0 * std::sqrt(p * (1.0 - p) / last.ess) + 2e-3;
    agree = agree && std::abs(estimate[k] - p) <= bound;
    std::printf("%7d  %.3f  %.4f  %.4f   %.4f\n", k + 1, prior.prior_one[k], p, estimate[k], bound);
  }
  std::printf("%s\n", agree ? "ABC-SMC agrees with the exact posterior" : "ABC-SMC disagrees");
  return agree ? 0 : 1;
}
