#include <memory>
#include <vector>

#include "combabc/core/check.hpp"
#include "combabc/proposals/proposal.hpp"

namespace combabc {
namespace {

// Wave 0 proposes from the prior itself: each real drawn from its own prior, in order, so the
// importance weight p / q is 1 and every draw is inside the support.
class PriorProposal final : public ContinuousProposal {
 public:
  explicit PriorProposal(const ParameterSpace& space) {
    for (const ContinuousParameter& p : space.reals()) priors_.push_back(p.prior);
  }
  void Sample(RandomStream& rng, std::span<double> reals) const override {
    COMBABC_CHECK(reals.size() == priors_.size());
    for (std::size_t k = 0; k < priors_.size(); ++k) reals[k] = priors_[k].Sample(rng);
  }
  double LogDensity(std::span<const double> reals) const override {
    COMBABC_CHECK(reals.size() == priors_.size());
    double sum = 0.0;
    for (std::size_t k = 0; k < priors_.size(); ++k) sum += priors_[k].LogDensity(reals[k]);
    return sum;
  }

 private:
  std::vector<ContinuousPrior> priors_;  // a copy: the proposal may outlive the space
};

}  // namespace

std::unique_ptr<ContinuousProposal> ContinuousKernel::Prior(const ParameterSpace& space) const {
  return std::make_unique<PriorProposal>(space);
}

}  // namespace combabc
