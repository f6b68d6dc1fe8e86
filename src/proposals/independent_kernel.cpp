#include "combabc/proposals/independent_kernel.hpp"

#include <algorithm>
#include <cmath>

#include "combabc/core/check.hpp"

namespace combabc {

BernoulliProposal::BernoulliProposal(std::vector<double> prob_one)
    : prob_one_(std::move(prob_one)) {
  for (const double q : prob_one_) {
    COMBABC_CHECK(q >= 0.0 && q <= 1.0);
    threshold_.push_back(BernoulliThreshold(q));
    // log 0 = -inf marks a value this proposal never draws.
    log_density_.push_back(std::log1p(-q));
    log_density_.push_back(std::log(q));
  }
}

void BernoulliProposal::Sample(RandomStream& rng, std::span<std::uint8_t> free_bits) const {
  for (std::size_t j = 0; j < threshold_.size(); ++j) {
    free_bits[j] = static_cast<std::uint8_t>(rng.Bernoulli53(threshold_[j]));
  }
}

double BernoulliProposal::LogDensity(std::span<const std::uint8_t> free_bits) const {
  double sum = 0.0;
  for (std::size_t j = 0; j < threshold_.size(); ++j) {
    sum += log_density_[2 * j + (free_bits[j] & 1U)];
  }
  return sum;
}

std::unique_ptr<BinaryProposal> BinaryKernel::Prior(const std::vector<double>& prior_one) const {
  return std::make_unique<BernoulliProposal>(prior_one);
}

namespace {

class IndependentKernel : public BinaryKernel {
 public:
  std::string name() const override { return "independent"; }
  // Eq. 2: P(bit j = 1) = the population's (weighted) fraction of 1s; then Eq. 3 toward the prior.
  std::unique_ptr<BinaryProposal> Fit(const Population& population,
                                      const std::vector<double>& prior_one,
                                      const Tempering& tempering) const override {
    const std::size_t f = prior_one.size();
    COMBABC_CHECK(population.num_free_bits == f);
    if (population.size == 0) return Prior(prior_one);
    std::vector<double> p_hat(f, 0.0);
    for (std::size_t i = 0; i < population.size; ++i) {
      const auto bits = population.bits_of(i);
      const double w = population.weights[i];
      for (std::size_t j = 0; j < f; ++j) {
        if (bits[j]) p_hat[j] += w;
      }
    }
    for (std::size_t j = 0; j < f; ++j) {
      p_hat[j] = TemperedProbability(
          std::clamp(p_hat[j], 0.0, 1.0), prior_one[j], tempering.phi, tempering.form);
    }
    return std::make_unique<BernoulliProposal>(std::move(p_hat));
  }
};

}  // namespace

std::unique_ptr<BinaryKernel> MakeIndependentKernel() {
  return std::make_unique<IndependentKernel>();
}

}  // namespace combabc
