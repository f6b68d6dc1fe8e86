// Noise-aware acceptance (Wilkinson 2013): with a negative log-likelihood component accepted with
// probability exp(-(d - m) / T), the last wave (T = 1) targets p(theta) exp(-d(theta)) exactly.
// On 8 bits that posterior is enumerable (256 configurations); the importance estimator must match
// it per bit within 5 Monte-Carlo standard errors, and the run must be identical for any thread
// count and batch size (the acceptance uniform comes from the candidate's own stream).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "combabc/core/error.hpp"
#include "combabc/samplers/combinatorial_smc.hpp"
#include "toy_models.hpp"

namespace combabc {
namespace {

constexpr int kBits = 8;

double Bound(double p, double ess) { return 5.0 * std::sqrt(p * (1.0 - p) / ess) + 2e-3; }

struct Case {
  std::vector<double> prior = {0.5, 0.3, 0.6, 0.5, 0.4, 0.7, 0.5, 0.2};
  // Six outputs, each a linear function of the bits; bits 6 and 7 enter only as their sum in
  // output 5 (partly confounded), bit 3 weakly.
  testing::LinearSimulator sim{{{1.0, 0.5, 0.0, 0.1, 0.0, 0.0, 0.0, 0.0},
                                {0.0, 1.0, 0.8, 0.0, 0.2, 0.0, 0.0, 0.0},
                                {0.3, 0.0, 1.0, 0.1, 0.0, 0.6, 0.0, 0.0},
                                {0.0, 0.0, 0.0, 0.1, 1.0, 0.4, 0.0, 0.0},
                                {0.5, 0.0, 0.0, 0.0, 0.0, 1.0, 0.2, 0.0},
                                {0.0, 0.2, 0.0, 0.0, 0.0, 0.0, 0.7, 0.7}}};
  // A theta_true for theta_true = 10110010 plus fixed perturbations (the "noise").
  testing::GaussianNllDistance dist{{1.25, 0.7, 1.3, 0.2, 0.75, 0.6}, 0.3};
  ParameterSpace space = [this] {
    BinarySpaceOptions o;
    o.dimension = kBits;
    o.prior_one = prior;
    return ParameterSpace(BinarySpace(o));
  }();

  std::vector<double> ExactMarginals() const {
    std::vector<double> m(kBits, 0.0);
    double z = 0.0;
    std::vector<double> y(6);
    double d = 0.0;
    RandomStream rng(0, 0, 0);
    for (int c = 0; c < (1 << kBits); ++c) {
      std::vector<std::uint8_t> bits(kBits);
      double p = 1.0;
      for (int k = 0; k < kBits; ++k) {
        bits[k] = (c >> k) & 1;
        p *= bits[k] != 0 ? prior[k] : 1.0 - prior[k];
      }
      sim.Simulate(ParameterView{bits, {}}, rng, y);
      dist.Evaluate(y, std::span(&d, 1));
      p *= std::exp(-d);
      z += p;
      for (int k = 0; k < kBits; ++k) m[k] += bits[k] * p;
    }
    for (auto& x : m) x /= z;
    return m;
  }

  SmcOptions Options(int threads) const {
    SmcOptions o;
    o.num_waves = 12;
    o.accepted_per_wave = 4000;
    o.seed = 2013;
    o.threads = threads;
    ThresholdSchedule s;  // temperatures: prior, then the median of d - m, down to 1
    s.target = 1.0;
    o.thresholds = {s};
    o.tempering.kind = TemperingKind::kLinear;
    o.tempering.phi0 = 0.5;
    return o;
  }
  RunHistory Run(const SmcOptions& o) const {
    return RunCombinatorialSmc({&space, &sim, &dist}, o);
  }
};

TEST(NoiseAware, LastWaveMatchesEnumeratedLikelihoodPosterior) {
  Case c;
  const auto exact = c.ExactMarginals();
  const auto h = c.Run(c.Options(2));
  ASSERT_EQ(h.summary.termination, Termination::kTargetReached);
  const auto& last = h.waves.back();
  ASSERT_EQ(last.thresholds[0], 1.0);
  ASSERT_GT(h.waves.size(), 2u);  // the temperature did fall through intermediate waves
  std::printf("waves %zu, temperatures:", h.waves.size());
  for (const auto& w : h.waves) std::printf(" %.3g", w.thresholds[0]);
  std::printf("\nbit  exact   importance  (ESS %.0f)\n", last.ess);
  int intermediate = 0;
  for (int k = 0; k < kBits; ++k) {
    const double imp = last.marginals_importance[k];
    std::printf("%3d  %.4f  %.4f\n", k, exact[k], imp);
    EXPECT_NEAR(imp, exact[k], Bound(exact[k], last.ess)) << "bit " << k;
    intermediate += exact[k] > 0.05 && exact[k] < 0.95;
  }
  EXPECT_GE(intermediate, 3);  // the case is not trivially certain
}

TEST(NoiseAware, ThresholdAcceptanceWouldBeDifferent) {
  // Sanity check of the test itself: the likelihood posterior differs from the prior and from
  // the point mass at the best configuration, so matching it means something.
  Case c;
  const auto exact = c.ExactMarginals();
  double from_prior = 0.0;
  for (int k = 0; k < kBits; ++k) {
    from_prior = std::max(from_prior, std::abs(exact[k] - c.prior[k]));
  }
  EXPECT_GT(from_prior, 0.2);
}

TEST(NoiseAware, IdenticalHistoriesForAnyThreadCountAndBatchSize) {
  Case c;
  auto o = c.Options(1);
  o.num_waves = 4;
  o.accepted_per_wave = 300;
  const auto reference = c.Run(o);
  ASSERT_EQ(reference.waves.size(), 4u);
  for (int threads : {2, 4, 16}) {
    o.threads = threads;
    std::string where;
    EXPECT_TRUE(SameHistory(reference, c.Run(o), &where)) << threads << " threads: " << where;
  }
  o.threads = 2;
  for (int batch : {1, 7, 5000}) {
    o.batch_size = batch;
    std::string where;
    EXPECT_TRUE(SameHistory(reference, c.Run(o), &where)) << "batch " << batch << ": " << where;
  }
}

TEST(NoiseAware, TemperatureBelowOneIsRejected) {
  Case c;
  auto o = c.Options(1);
  o.thresholds[0].target = 0.5;
  EXPECT_THROW(c.Run(o), Error);
}

}  // namespace
}  // namespace combabc
