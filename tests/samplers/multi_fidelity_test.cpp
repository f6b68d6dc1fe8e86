// Multi-fidelity ABC-SMC (docs/algorithm.md, "Multi-fidelity sampling"): on 8 bits the expensive
// model's ABC posterior is computable by enumerating all 256 configurations. A cheap model that is
// wrong on some bits decides most candidates; the continuation weights must still give the
// *expensive* model's posterior, not the cheap one's.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdio>

#include "combabc/core/error.hpp"
#include "combabc/samplers/combinatorial_smc.hpp"
#include "toy_models.hpp"

namespace combabc {
namespace {

constexpr int kBits = 8;
constexpr double kFinalEps = 2.5;

// 5 standard errors of wave's estimate of P(bit k = 1), plus a small floor. The standard error of
// a self-normalised estimate sum_i w_i b_i (weights normalised to sum 1) is
// sqrt(sum_i w_i^2 (b_i - m)^2) to first order; unlike p(1-p)/ESS it holds for signed weights,
// whose noise does not vanish at a marginal of 0 or 1. Fixed seeds make the check deterministic;
// the margin makes it robust to any change of the random streams.
double Bound(const WaveRecord& wave, int k) {
  const double m = wave.marginals_importance[static_cast<std::size_t>(k)];
  double var = 0.0;
  for (const auto& p : wave.particles) {
    const double dev = p.theta.bits[static_cast<std::size_t>(k)] - m;
    var += p.weight * p.weight * dev * dev;
  }
  return 5.0 * std::sqrt(var) + 0.005;
}

// Output = the bits; with `flipped`, those bits are reported inverted and output 0 is shifted by
// `shift`: a biased cheap model. Counts its calls.
class ToySimulator : public Simulator {
 public:
  explicit ToySimulator(std::vector<int> flipped = {}, double shift = 0.0)
      : flipped_(std::move(flipped)), shift_(shift) {}
  int output_size() const override { return kBits; }
  void Simulate(const ParameterView& theta,
                RandomStream& /*rng*/,
                std::span<double> out) const override {
    calls_.fetch_add(1, std::memory_order_relaxed);
    for (int k = 0; k < kBits; ++k) out[k] = theta.bits[k];
    for (int k : flipped_) out[k] = 1.0 - out[k];
    out[0] += shift_;
  }
  std::int64_t calls() const { return calls_.load(); }

 private:
  std::vector<int> flipped_;
  double shift_;
  mutable std::atomic<std::int64_t> calls_{0};
};

struct Toy {
  std::vector<double> prior = {0.5, 0.3, 0.6, 0.5, 0.4, 0.7, 0.5, 0.35};
  // Bit 7 weighs 0: its posterior is its prior.
  testing::WeightedL1Distance dist{{1, 0, 1, 1, 0, 0, 1, 0}, {3, 2, 2, 1.5, 1, 1, 1, 0}};
  ToySimulator expensive;
  ParameterSpace space = [this] {
    BinarySpaceOptions o;
    o.dimension = kBits;
    o.prior_one = prior;
    return ParameterSpace(BinarySpace(o));
  }();

  // The exact ABC posterior marginals of `model` at kFinalEps.
  std::vector<double> ExactMarginals(const Simulator& model) const {
    std::vector<double> m(kBits, 0.0);
    double z = 0.0;
    std::vector<double> y(kBits);
    std::vector<std::uint8_t> bits(kBits);
    double d = 0.0;
    RandomStream rng(0, 0, 0);
    for (int c = 0; c < (1 << kBits); ++c) {
      double p = 1.0;
      for (int k = 0; k < kBits; ++k) {
        bits[k] = static_cast<std::uint8_t>((c >> k) & 1);
        p *= bits[k] != 0 ? prior[k] : 1.0 - prior[k];
      }
      model.Simulate(ParameterView{bits, {}}, rng, y);
      dist.Evaluate(y, std::span(&d, 1));
      if (d > kFinalEps) continue;
      z += p;
      for (int k = 0; k < kBits; ++k) m[k] += bits[k] * p;
    }
    for (auto& x : m) x /= z;
    return m;
  }

  SmcOptions Options(double eta_accepted, double eta_rejected, int threads) const {
    SmcOptions o;
    o.num_waves = 4;
    o.accepted_per_wave = 2000;
    o.seed = 24;
    o.threads = threads;
    ThresholdSchedule s;
    s.kind = ThresholdKind::kList;
    s.values = {8, 5, 3.5, kFinalEps};
    o.thresholds = {s};
    o.multi_fidelity.continue_if_accepted = eta_accepted;
    o.multi_fidelity.continue_if_rejected = eta_rejected;
    return o;
  }
};

TEST(MultiFidelity, BiasedCheapModelGivesExpensivePosterior) {
  Toy toy;
  // Wrong on bits 2 and 5 and shifted on output 0: its own posterior is far from the truth.
  const ToySimulator cheap({2, 5}, 0.3);
  const auto exact = toy.ExactMarginals(toy.expensive);
  const auto cheap_exact = toy.ExactMarginals(cheap);
  EXPECT_NEAR(exact[7], 0.35, 1e-12);                   // unidentifiable bit: posterior = prior
  EXPECT_GT(std::abs(cheap_exact[2] - exact[2]), 0.3);  // the test can tell them apart

  const std::int64_t cheap_before = cheap.calls();
  const std::int64_t expensive_before = toy.expensive.calls();
  SmcProblem problem{&toy.space, &toy.expensive, &toy.dist};
  problem.low_fidelity = &cheap;
  // eta_1 < 1: cheap acceptances the expensive model rejects get negative weights.
  const auto history = RunCombinatorialSmc(problem, toy.Options(0.5, 0.3, 2));
  ASSERT_EQ(history.summary.termination, Termination::kTargetReached);
  const auto& last = history.waves.back();
  ASSERT_EQ(last.thresholds[0], kFinalEps);
  int negative = 0;
  for (const auto& p : last.particles) negative += p.multiplier < 0;
  EXPECT_GT(negative, 0);
  std::printf("bit  exact   multi-fidelity  cheap-only exact  (ESS %.0f, %d negative)\n",
              last.ess,
              negative);
  for (int k = 0; k < kBits; ++k) {
    const double mf = last.marginals_importance[k];
    std::printf("%3d  %.4f  %.4f          %.4f\n", k, exact[k], mf, cheap_exact[k]);
    EXPECT_NEAR(mf, exact[k], Bound(last, k)) << "bit " << k;
  }
  // The expensive model ran on a fraction of the candidates only.
  const std::int64_t cheap_calls = cheap.calls() - cheap_before;
  EXPECT_EQ(cheap_calls, history.summary.simulations + history.summary.simulations_discarded);
  EXPECT_LT(toy.expensive.calls() - expensive_before, cheap_calls);
}

TEST(MultiFidelity, PerfectCheapModelRarelyCallsTheExpensiveOne) {
  Toy toy;
  const ToySimulator cheap;  // the expensive model itself: never wrong
  SmcProblem problem{&toy.space, &toy.expensive, &toy.dist};
  problem.low_fidelity = &cheap;
  const auto history = RunCombinatorialSmc(problem, toy.Options(0.05, 0.05, 1));
  ASSERT_EQ(history.summary.termination, Termination::kTargetReached);
  const std::int64_t cheap_calls = cheap.calls();
  EXPECT_EQ(cheap_calls, history.summary.simulations + history.summary.simulations_discarded);
  // About 5 % continue; 10 % bounds it far beyond Monte-Carlo error at these counts.
  EXPECT_GT(toy.expensive.calls(), 0);
  EXPECT_LT(toy.expensive.calls(), cheap_calls / 10);
  // Both models agree: every weight multiplier is exactly 1 and the posterior is exact.
  const auto& last = history.waves.back();
  for (const auto& p : last.particles) ASSERT_EQ(p.multiplier, 1.0);
  const auto exact = toy.ExactMarginals(toy.expensive);
  for (int k = 0; k < kBits; ++k) {
    EXPECT_NEAR(last.marginals_importance[k], exact[k], Bound(last, k)) << "bit " << k;
  }
}

TEST(MultiFidelity, SameHistoryForOneAndTwoThreads) {
  Toy toy;
  const ToySimulator cheap({2, 5}, 0.3);
  SmcProblem problem{&toy.space, &toy.expensive, &toy.dist};
  problem.low_fidelity = &cheap;
  auto options = toy.Options(0.5, 0.3, 1);
  options.accepted_per_wave = 500;
  const auto one = RunCombinatorialSmc(problem, options);
  options.threads = 2;
  const auto two = RunCombinatorialSmc(problem, options);
  std::string where;
  EXPECT_TRUE(SameHistory(one, two, &where)) << where;
  ASSERT_FALSE(one.waves.empty());
  EXPECT_GT(one.waves.back().particles.size(), 0U);
}

TEST(MultiFidelity, ContinuationProbabilitiesMustBeInZeroOne) {
  for (double eta : {0.0, -0.1, 1.5, std::nan("")}) {
    SmcOptions o;
    o.multi_fidelity.continue_if_rejected = eta;
    std::string why;
    EXPECT_FALSE(o.IsValid(&why)) << eta;
    EXPECT_NE(why.find("SmcOptions::multi_fidelity.continue_if_rejected"), std::string::npos)
        << why;
  }
  SmcOptions o;
  o.multi_fidelity.continue_if_accepted = 1.0;
  o.multi_fidelity.continue_if_rejected = 1e-3;
  std::string why;
  EXPECT_TRUE(o.IsValid(&why)) << why;
}

TEST(MultiFidelity, WeightMultiplier) {
  MultiFidelityOptions o;
  o.continue_if_accepted = 0.5;
  o.continue_if_rejected = 0.25;
  EXPECT_EQ(MultiFidelityMultiplier(o, true, false, false), 1.0);
  EXPECT_EQ(MultiFidelityMultiplier(o, false, false, false), 0.0);
  EXPECT_EQ(MultiFidelityMultiplier(o, true, true, true), 1.0);
  EXPECT_EQ(MultiFidelityMultiplier(o, true, true, false), -1.0);  // 1 - 1 / 0.5
  EXPECT_EQ(MultiFidelityMultiplier(o, false, true, true), 4.0);   // 1 / 0.25
  EXPECT_EQ(MultiFidelityMultiplier(o, false, true, false), 0.0);
}

TEST(MultiFidelity, LowFidelityOutputsMustMatch) {
  Toy toy;
  const testing::IdentitySimulator cheap(kBits + 1);
  SmcProblem problem{&toy.space, &toy.expensive, &toy.dist};
  problem.low_fidelity = &cheap;
  try {
    RunCombinatorialSmc(problem, toy.Options(1.0, 0.1, 1));
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kConfig);
    EXPECT_NE(std::string(e.what()).find("low_fidelity"), std::string::npos) << e.what();
  }
}

// Fails every candidate with bit 1 set.
class FailingSimulator : public Simulator {
 public:
  int output_size() const override { return kBits; }
  void Simulate(const ParameterView& theta,
                RandomStream& /*rng*/,
                std::span<double> out) const override {
    if (theta.bits[1] != 0) throw SimulationFailed("bit 1 breaks the solver");
    for (int k = 0; k < kBits; ++k) out[k] = theta.bits[k];
  }
};

TEST(MultiFidelity, AFailedExpensiveSimulationFailsTheCandidate) {
  Toy toy;
  const FailingSimulator expensive;
  SmcProblem problem{&toy.space, &expensive, &toy.dist};
  problem.low_fidelity = &toy.expensive;    // never fails
  auto options = toy.Options(1.0, 1.0, 2);  // every candidate continues
  options.num_waves = 1;
  options.thresholds[0].values = {kFinalEps};
  options.accepted_per_wave = 200;
  options.max_failure_fraction = 1.0;
  const auto history = RunCombinatorialSmc(problem, options);
  const auto& wave = history.waves.front();
  ASSERT_FALSE(wave.failures.empty());
  EXPECT_EQ(wave.failures.front().reason, "bit 1 breaks the solver");
  for (const auto& p : wave.particles) EXPECT_EQ(p.theta.bits[1], 0);
}

}  // namespace
}  // namespace combabc
