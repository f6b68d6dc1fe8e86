#pragma once
// The combinatorial proposal (paper Eq. 2, tempered by Eq. 3): an independent Bernoulli per free
// bit. BernoulliProposal is also every binary kernel's prior proposal (wave 0).
#include <cstdint>
#include <span>
#include <vector>

#include "combabc/proposals/proposal.hpp"

namespace combabc {

class BernoulliProposal : public BinaryProposal {
 public:
  // prob_one[j] = P(free bit j = 1), each in [0, 1].
  explicit BernoulliProposal(std::vector<double> prob_one);

  void Sample(RandomStream& rng, std::span<std::uint8_t> free_bits) const override;
  double LogDensity(std::span<const std::uint8_t> free_bits) const override;
  std::vector<double> Marginals() const override { return prob_one_; }

 private:
  std::vector<double> prob_one_;
  std::vector<std::uint64_t> threshold_;  // BernoulliThreshold(prob_one_[j])
  // log q of free bit j = v at [2 j + v]: a lookup, not a branch on random bits.
  std::vector<double> log_density_;
};

}  // namespace combabc
