#pragma once
// The combinatorial proposal (paper Eq. 2, tempered by Eq. 3): independent Bernoulli per free
// parameter. Also its density, for importance weights p(theta)/q(theta).
#include <cstdint>
#include <span>
#include <vector>

#include "combabc/rng/random_stream.hpp"

namespace combabc {

class BernoulliProposal {
 public:
  // prob_one[j] = P(free parameter j = 1); prior_one[j] = its prior P(1) (for weights).
  BernoulliProposal(std::vector<double> prob_one, const std::vector<double>& prior_one);

  const std::vector<double>& prob_one() const { return prob_one_; }
  int size() const { return static_cast<int>(prob_one_.size()); }

  void Sample(RandomStream& rng, std::span<std::uint8_t> free) const;
  // log p(theta) - log q(theta) over the free parameters. Finite whenever q(theta) > 0, which
  // holds for anything Sample() returns.
  double LogWeight(std::span<const std::uint8_t> free) const;

 private:
  std::vector<double> prob_one_;
  std::vector<std::uint64_t> threshold_;  // BernoulliThreshold(prob_one_[j])
  std::vector<double> log_ratio_one_;     // log(prior/q) for value 1
  std::vector<double> log_ratio_zero_;    // log((1-prior)/(1-q)) for value 0
};

}  // namespace combabc
