// The product of a binary and a continuous kernel as one JointKernel (proposal.hpp).
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "combabc/core/check.hpp"
#include "combabc/proposals/proposal.hpp"

namespace combabc {
namespace {

// q(b, r) = q_bits(b) q_reals(r); `reals` is null for a space without reals.
class ProductProposal final : public JointProposal {
 public:
  ProductProposal(std::unique_ptr<BinaryProposal> bits, std::unique_ptr<ContinuousProposal> reals)
      : bits_(std::move(bits)), reals_(std::move(reals)) {}

  void Sample(RandomStream& rng,
              std::span<std::uint8_t> free_bits,
              std::span<double> reals) const override {
    bits_->Sample(rng, free_bits);
    if (reals_) reals_->Sample(rng, reals);
  }
  double LogDensity(std::span<const std::uint8_t> free_bits,
                    std::span<const double> reals) const override {
    const double bits = bits_->LogDensity(free_bits);
    return reals_ ? bits + reals_->LogDensity(reals) : bits;
  }
  double LogBitsDensity(std::span<const std::uint8_t> free_bits) const override {
    return bits_->LogDensity(free_bits);
  }
  std::vector<double> Marginals() const override { return bits_->Marginals(); }

 private:
  std::unique_ptr<BinaryProposal> bits_;
  std::unique_ptr<ContinuousProposal> reals_;
};

class ProductKernel final : public JointKernel {
 public:
  ProductKernel(std::unique_ptr<BinaryKernel> bits, std::unique_ptr<ContinuousKernel> reals)
      : bits_(std::move(bits)), reals_(std::move(reals)) {
    COMBABC_CHECK(bits_ && reals_);
  }

  std::string name() const override { return bits_->name(); }

  std::unique_ptr<JointProposal> Prior(const ParameterSpace& space) const override {
    return std::make_unique<ProductProposal>(
        bits_->Prior(space.binary().free_prior_one()),
        space.num_reals() > 0 ? reals_->Prior(space) : nullptr);
  }

  std::unique_ptr<JointProposal> Fit(const Population& population,
                                     const ParameterSpace& space,
                                     const Tempering& tempering) const override {
    return std::make_unique<ProductProposal>(
        bits_->Fit(population, space.binary().free_prior_one(), tempering),
        space.num_reals() > 0 ? reals_->Fit(population, space) : nullptr);
  }

 private:
  std::unique_ptr<BinaryKernel> bits_;
  std::unique_ptr<ContinuousKernel> reals_;
};

}  // namespace

std::unique_ptr<JointKernel> MakeProductKernel(std::unique_ptr<BinaryKernel> bits,
                                               std::unique_ptr<ContinuousKernel> reals) {
  return std::make_unique<ProductKernel>(std::move(bits), std::move(reals));
}

}  // namespace combabc
