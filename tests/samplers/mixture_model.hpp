#pragma once
// Sisson, Fan & Tanaka's (2007) mixture toy as Beaumont et al. (2009) ran it: theta ~ U(-10, 10),
// x ~ 0.5 N(theta, 1) + 0.5 N(theta, 0.1^2), x* = 0, distance |x - x*| (linear_gaussian.hpp's
// AbsoluteDistance). Its ABC posterior at eps, p(theta) P(|x| <= eps | theta), is heavy-tailed
// (a narrow spike on a wide bump): the case where importance weights go with the quantity
// estimated. Shared by the Monte-Carlo error coverage test and bench_engine_coverage.
#include <cmath>
#include <span>

#include "combabc/samplers/simulator.hpp"
#include "linear_gaussian.hpp"

namespace combabc::testing {

class MixtureSimulator : public Simulator {
 public:
  int output_size() const override { return 1; }
  void Simulate(const ParameterView& theta,
                RandomStream& rng,
                std::span<double> out) const override {
    const double sd = rng.Uniform() < 0.5 ? 1.0 : 0.1;
    out[0] = theta.reals[0] + sd * rng.Normal();
  }
};

inline ContinuousPrior MixturePrior() {
  ContinuousPrior prior;
  prior.kind = PriorKind::kUniform;
  prior.low = -10.0;
  prior.high = 10.0;
  return prior;
}

// The exact posterior mean and sd at eps: each component's ABC posterior by quadrature
// (ExactPosterior without bits), mixed half and half, since both components' evidence is the
// same 2 eps / 20 (the flat prior reaches far beyond either).
struct MixtureMoments {
  double mean = 0.0;
  double sd = 0.0;
};
inline MixtureMoments ExactMixtureMoments(double eps) {
  const ContinuousPrior prior = MixturePrior();
  const Exact wide = ExactPosterior({}, {}, prior, 1.0, 0.0, eps, -10.0, 10.0);
  const Exact narrow = ExactPosterior({}, {}, prior, 0.1, 0.0, eps, -10.0, 10.0);
  MixtureMoments m;
  m.mean = 0.5 * (wide.mean + narrow.mean);
  const double second =
      0.5 * (wide.var + wide.mean * wide.mean) + 0.5 * (narrow.var + narrow.mean * narrow.mean);
  m.sd = std::sqrt(second - m.mean * m.mean);
  return m;
}

}  // namespace combabc::testing
