#include "combabc/proposals/bernoulli_proposal.hpp"

#include <cmath>
#include <limits>

#include "combabc/core/check.hpp"

namespace combabc {
namespace {

// log(a / b) for probabilities, with the conventions a value of probability 0 under q is never
// sampled (so its ratio is never used: +inf marks it) and 0/0 likewise.
double LogRatio(double prior, double q) {
  if (q <= 0.0) return std::numeric_limits<double>::infinity();
  if (prior <= 0.0) return -std::numeric_limits<double>::infinity();
  return std::log(prior) - std::log(q);
}

}  // namespace

BernoulliProposal::BernoulliProposal(std::vector<double> prob_one,
                                     const std::vector<double>& prior_one)
    : prob_one_(std::move(prob_one)) {
  COMBABC_CHECK(prob_one_.size() == prior_one.size());
  for (std::size_t j = 0; j < prob_one_.size(); ++j) {
    const double q = prob_one_[j];
    COMBABC_CHECK(q >= 0.0 && q <= 1.0);
    threshold_.push_back(BernoulliThreshold(q));
    log_ratio_one_.push_back(LogRatio(prior_one[j], q));
    log_ratio_zero_.push_back(LogRatio(1.0 - prior_one[j], 1.0 - q));
  }
}

void BernoulliProposal::Sample(RandomStream& rng, std::span<std::uint8_t> free) const {
  for (std::size_t j = 0; j < threshold_.size(); ++j) {
    free[j] = static_cast<std::uint8_t>(rng.Bernoulli53(threshold_[j]));
  }
}

double BernoulliProposal::LogWeight(std::span<const std::uint8_t> free) const {
  double sum = 0.0;
  for (std::size_t j = 0; j < threshold_.size(); ++j) {
    sum += free[j] ? log_ratio_one_[j] : log_ratio_zero_[j];
  }
  return sum;
}

}  // namespace combabc
