// Multi-fidelity ABC-SMC (docs/algorithm.md, "Multi-fidelity sampling"): on 8 bits the expensive
// model's ABC posterior is computable by enumerating all 256 configurations. A cheap model that is
// wrong on some bits decides most candidates; the continuation weights must still give the
// *expensive* model's posterior, not the cheap one's.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <string>

#include "checkpoints.hpp"
#include "combabc/core/error.hpp"
#include "combabc/samplers/combinatorial_smc.hpp"
#include "toy_models.hpp"

namespace combabc {
namespace {

constexpr int kBits = 8;
constexpr double kFinalEps = 2.5;

// 5 standard errors of the wave's estimate sum_i w_i f(particle i) (weights normalised to sum 1),
// plus a small floor. Its standard error is sqrt(sum_i w_i^2 (f_i - m)^2) to first order; unlike
// p(1-p)/ESS it holds for signed weights, whose noise does not vanish at a marginal of 0 or 1.
// Fixed seeds make the check deterministic; the margin makes it robust to any change of the
// random streams.
template <typename F>
double Bound(const WaveRecord& wave, F f) {
  double m = 0.0;
  for (const auto& p : wave.particles) m += p.weight * f(p);
  double var = 0.0;
  for (const auto& p : wave.particles) var += p.weight * p.weight * (f(p) - m) * (f(p) - m);
  return 5.0 * std::sqrt(var) + 0.005;
}
double Bound(const WaveRecord& wave, int k) {
  return Bound(wave, [k](const Particle& p) { return p.theta.bits[static_cast<std::size_t>(k)]; });
}

// Output = the bits; with `flipped`, those bits are reported inverted, output 0 is shifted by
// `shift` and every output gets N(0, noise^2): a biased or noisier cheap model. Counts its calls.
class ToySimulator : public Simulator {
 public:
  explicit ToySimulator(std::vector<int> flipped = {}, double shift = 0.0, double noise = 0.0)
      : flipped_(std::move(flipped)), shift_(shift), noise_(noise) {}
  int output_size() const override { return kBits; }
  void Simulate(const ParameterView& theta,
                RandomStream& rng,
                std::span<double> out) const override {
    calls_.fetch_add(1, std::memory_order_relaxed);
    for (int k = 0; k < kBits; ++k) out[k] = theta.bits[k];
    for (int k : flipped_) out[k] = 1.0 - out[k];
    out[0] += shift_;
    if (noise_ > 0.0) {
      for (auto& y : out) y += noise_ * rng.Normal();
    }
  }
  std::int64_t calls() const { return calls_.load(); }

 private:
  std::vector<int> flipped_;
  double shift_;
  double noise_;
  mutable std::atomic<std::int64_t> calls_{0};
};

// A cheap model blind to bits 0 and 3: it reports their observed values whatever they are, so
// it accepts every candidate the expensive model accepts and more (false positives, no false
// negatives).
class BlindSimulator : public Simulator {
 public:
  int output_size() const override { return kBits; }
  void Simulate(const ParameterView& theta,
                RandomStream& /*rng*/,
                std::span<double> out) const override {
    for (int k = 0; k < kBits; ++k) out[k] = theta.bits[k];
    out[0] = 1.0;
    out[3] = 1.0;
  }
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
    // A known cost ratio: deterministic tuning (a measured one is not).
    o.multi_fidelity.cost_ratio = 20.0;
    return o;
  }
};

enum class CheapKind { kBiased, kNoisy };
struct ExactnessCase {
  BinaryKernelKind kernel;
  CheapKind cheap;
  bool adapt;
};

class MultiFidelityExactness : public ::testing::TestWithParam<ExactnessCase> {};

TEST_P(MultiFidelityExactness, BiasedCheapModelGivesExpensivePosterior) {
  const auto c = GetParam();
  Toy toy;
  // Biased: wrong on bits 2 and 5 and shifted on output 0 (its own posterior is far from the
  // truth). Noisy: N(0, 0.15^2) on every output.
  const ToySimulator cheap =
      c.cheap == CheapKind::kBiased ? ToySimulator({2, 5}, 0.3) : ToySimulator({}, 0.0, 0.15);
  const auto exact = toy.ExactMarginals(toy.expensive);
  EXPECT_NEAR(exact[7], 0.35, 1e-12);  // unidentifiable bit: posterior = prior
  if (c.cheap == CheapKind::kBiased) {
    EXPECT_GT(std::abs(toy.ExactMarginals(cheap)[2] - exact[2]), 0.3);  // tells them apart
  }
  const std::int64_t cheap_before = cheap.calls();
  const std::int64_t expensive_before = toy.expensive.calls();
  SmcProblem problem{&toy.space, &toy.expensive, &toy.dist};
  problem.low_fidelity = &cheap;
  // eta_1 < 1: cheap acceptances the expensive model rejects get negative weights.
  auto options = toy.Options(0.5, 0.3, 2);
  options.proposal.binary = c.kernel;
  options.multi_fidelity.adapt = c.adapt;
  const auto history = RunCombinatorialSmc(problem, options);
  ASSERT_EQ(history.summary.termination, Termination::kTargetReached);
  const auto& last = history.waves.back();
  ASSERT_EQ(last.thresholds[0], kFinalEps);
  int negative = 0;
  for (const auto& p : last.particles) negative += p.multiplier < 0;
  if (!c.adapt && c.cheap == CheapKind::kBiased) {
    EXPECT_GT(negative, 0);
  }
  std::printf("%s, %s cheap, adapt %d: eta per wave",
              ToString(c.kernel),
              c.cheap == CheapKind::kBiased ? "biased" : "noisy",
              c.adapt);
  for (const auto& w : history.waves) {
    std::printf(" (%.3f, %.3f)",
                w.multi_fidelity->continue_if_accepted,
                w.multi_fidelity->continue_if_rejected);
  }
  std::printf("; ESS %.0f, %d negative\n", last.ess, negative);
  for (int k = 0; k < kBits; ++k) {
    EXPECT_NEAR(last.marginals_importance[k], exact[k], Bound(last, k)) << "bit " << k;
  }
  // The expensive model ran on a fraction of the candidates only, and the waves count each of
  // its runs they consumed.
  const std::int64_t cheap_calls = cheap.calls() - cheap_before;
  const std::int64_t expensive_calls = toy.expensive.calls() - expensive_before;
  EXPECT_EQ(cheap_calls, history.summary.simulations + history.summary.simulations_discarded);
  if (!c.adapt) {
    EXPECT_LT(expensive_calls, cheap_calls / 2);
  } else if (c.cheap == CheapKind::kBiased) {
    // So wrong at the final thresholds that the expensive model alone is the most efficient:
    // tuning finds it (the errors' weight outweighs the agreement's, k <= 0).
    EXPECT_EQ(last.multi_fidelity->continue_if_accepted, 1.0);
  }
  std::int64_t recorded = 0;
  for (const auto& w : history.waves) recorded += w.multi_fidelity->expensive_simulations;
  EXPECT_LE(recorded, expensive_calls);
  EXPECT_GT(recorded, 0);
}

INSTANTIATE_TEST_SUITE_P(
    Cases,
    MultiFidelityExactness,
    ::testing::Values(ExactnessCase{BinaryKernelKind::kIndependent, CheapKind::kBiased, false},
                      ExactnessCase{BinaryKernelKind::kIndependent, CheapKind::kBiased, true},
                      ExactnessCase{BinaryKernelKind::kLogistic, CheapKind::kBiased, false},
                      ExactnessCase{BinaryKernelKind::kLogistic, CheapKind::kBiased, true},
                      ExactnessCase{BinaryKernelKind::kIndependent, CheapKind::kNoisy, true},
                      ExactnessCase{BinaryKernelKind::kLogistic, CheapKind::kNoisy, true}),
    [](const auto& test) {
      return std::string(ToString(test.param.kernel)) +
             (test.param.cheap == CheapKind::kBiased ? "Biased" : "Noisy") +
             (test.param.adapt ? "Tuned" : "Fixed");
    });

// From the default start (eta_1 = 1) every false positive weighs 0 and is no particle: the
// tuning still sees them (WaveFidelity::unkept_false_positives), so a cheap model that is often
// wrong does not get its acceptances left unchecked in wave 2.
TEST(MultiFidelity, TuningSeesTheFalsePositivesThatWeighNothing) {
  Toy toy;
  const BlindSimulator cheap;
  SmcProblem problem{&toy.space, &toy.expensive, &toy.dist};
  problem.low_fidelity = &cheap;
  const MultiFidelityOptions defaults;
  auto options = toy.Options(defaults.continue_if_accepted, defaults.continue_if_rejected, 1);
  const auto history = RunCombinatorialSmc(problem, options);
  ASSERT_GE(history.waves.size(), 2U);
  const auto& first = *history.waves[0].multi_fidelity;
  EXPECT_GT(first.unkept_false_positives, 100);
  for (const auto& p : history.waves[0].particles) EXPECT_NE(p.multiplier, 0.0);
  // Without them the tuning saw no false positive in wave 1 and lowered eta_1 (0.376), whose
  // confirmed false positives then weighed 1 - 1 / eta_1, and the ESS fell to 446 of 2000 in
  // wave 2 and to 9 in wave 4; with them eta_1 stays 1 and every wave keeps an ESS above 1700.
  EXPECT_GT(history.waves[1].multi_fidelity->continue_if_accepted, 0.9);
  for (const auto& w : history.waves) EXPECT_GT(w.ess, 1000.0) << "wave " << w.wave + 1;
  const auto exact = toy.ExactMarginals(toy.expensive);
  const auto& last = history.waves.back();
  for (int k = 0; k < kBits; ++k) {
    EXPECT_NEAR(last.marginals_importance[k], exact[k], Bound(last, k)) << "bit " << k;
  }
}

// A wave whose every threshold is infinite accepts whatever either model says: the expensive
// one runs on a share continue_if_rejected of its candidates only (not continue_if_accepted = 1,
// which would confirm them all for nothing), every particle weighs 1, and the run still ends at
// the expensive model's posterior.
TEST(MultiFidelity, AnInfiniteThresholdWaveConfirmsAShareOnly) {
  Toy toy;
  const ToySimulator cheap({2, 5}, 0.3);
  SmcProblem problem{&toy.space, &toy.expensive, &toy.dist};
  problem.low_fidelity = &cheap;
  auto options = toy.Options(1.0, 0.1, 1);
  options.thresholds[0].values = {std::numeric_limits<double>::infinity(), 5, 3.5, kFinalEps};
  const auto history = RunCombinatorialSmc(problem, options);
  ASSERT_EQ(history.summary.termination, Termination::kTargetReached);
  const auto& first = history.waves[0];
  const double share = static_cast<double>(first.multi_fidelity->expensive_simulations) /
                       static_cast<double>(first.candidates);
  EXPECT_GT(share, 0.07);
  EXPECT_LT(share, 0.13);
  for (const auto& p : first.particles) EXPECT_EQ(p.multiplier, 1.0);
  const auto exact = toy.ExactMarginals(toy.expensive);
  const auto& last = history.waves.back();
  for (int k = 0; k < kBits; ++k) {
    EXPECT_NEAR(last.marginals_importance[k], exact[k], Bound(last, k)) << "bit " << k;
  }
}

// The tuning lowers an eta only from at least 20 confirmed candidates of its class: a first wave
// of 100 at infinite thresholds confirms about 10 (continue_if_rejected = 0.1), all accepted by
// the cheap model, so wave 2 keeps eta_1 = 1 however good those few looked (the trap: "no error
// seen" in a handful sent eta_1 to the floor and kept the cheap model's answer).
TEST(MultiFidelity, FewConfirmationsNeverLowerAContinuationProbability) {
  Toy toy;
  const ToySimulator cheap;  // never wrong: the tuning would lower both at once
  SmcProblem problem{&toy.space, &toy.expensive, &toy.dist};
  problem.low_fidelity = &cheap;
  auto options = toy.Options(1.0, 0.1, 1);
  options.accepted_per_wave = 100;
  options.thresholds[0].values = {std::numeric_limits<double>::infinity(), 5, 3.5, kFinalEps};
  const auto history = RunCombinatorialSmc(problem, options);
  ASSERT_GE(history.waves.size(), 3U);
  const auto& first = *history.waves[0].multi_fidelity;
  ASSERT_LT(first.expensive_simulations, 20);
  EXPECT_EQ(first.next_continue_if_accepted, 1.0);
  EXPECT_EQ(first.next_continue_if_rejected, 0.1);
  // Wave 2 confirms every cheap acceptance (about 100 or more): from there it may lower eta_1.
  const auto& second = *history.waves[1].multi_fidelity;
  EXPECT_GE(second.expensive_simulations, 100);
  EXPECT_EQ(second.next_continue_if_accepted, options.multi_fidelity.floor);
}

// A cheap model that accepts every candidate (it reports the observed outputs), confirmed at
// eta_1 = 0.1: the expensive model rejects most, their multipliers 1 - 1 / eta_1 = -9 cancel the
// others', and the wave's effective count stays near 0.4 % of its particles. It stops at
// kMultiFidelityParticlesPerAccepted x n particles; before, it grew until the count reached n
// (on the sensor: waves of 200, 12,796, 144,985 and 842,019 particles, 2.2 GB).
TEST(MultiFidelity, AWaveWhoseWeightsCancelStopsAtItsParticleCap) {
  Toy toy;
  class AcceptsAll : public Simulator {
   public:
    int output_size() const override { return kBits; }
    void Simulate(const ParameterView&, RandomStream&, std::span<double> out) const override {
      const double observed[kBits] = {1, 0, 1, 1, 0, 0, 1, 0};  // the distance's target
      std::copy(observed, observed + kBits, out.begin());
    }
  } cheap;
  SmcProblem problem{&toy.space, &toy.expensive, &toy.dist};
  problem.low_fidelity = &cheap;
  auto options = toy.Options(0.1, 0.1, 1);
  options.multi_fidelity.adapt = false;
  options.num_waves = 1;
  options.accepted_per_wave = 20;
  options.thresholds[0].values = {kFinalEps};
  const auto history = RunCombinatorialSmc(problem, options);
  ASSERT_EQ(history.waves.size(), 1U);
  const WaveRecord& wave = history.waves[0];
  EXPECT_FALSE(wave.complete);
  EXPECT_EQ(wave.particles.size(),
            static_cast<std::size_t>(kMultiFidelityParticlesPerAccepted * 20));
  EXPECT_EQ(history.summary.termination, Termination::kTooManyParticles);
  EXPECT_NE(history.summary.message.find("wave 1 kept 400 particles (20 x the 20 it needs)"),
            std::string::npos)
      << history.summary.message;
}

TEST(MultiFidelity, PerfectCheapModelRarelyCallsTheExpensiveOne) {
  Toy toy;
  const ToySimulator cheap;  // the expensive model itself: never wrong
  SmcProblem problem{&toy.space, &toy.expensive, &toy.dist};
  problem.low_fidelity = &cheap;
  // The defaults (eta 1 and 0.1 for the first wave), tuned from then on.
  auto options = toy.Options(1.0, 0.1, 1);
  options.multi_fidelity.cost_ratio = 100.0;
  const auto history = RunCombinatorialSmc(problem, options);
  ASSERT_EQ(history.summary.termination, Termination::kTargetReached);
  // No false positive or negative: tuning puts both probabilities at the floor after wave 0.
  for (std::size_t t = 1; t < history.waves.size(); ++t) {
    const auto& f = *history.waves[t].multi_fidelity;
    EXPECT_EQ(f.continue_if_accepted, options.multi_fidelity.floor) << "wave " << t;
    EXPECT_EQ(f.continue_if_rejected, options.multi_fidelity.floor) << "wave " << t;
    // About 10 % (the default floor) continue; 13 % bounds it far beyond Monte-Carlo error at
    // these counts.
    EXPECT_LT(f.expensive_simulations, history.waves[t].candidates * 13 / 100) << "wave " << t;
  }
  EXPECT_EQ(cheap.calls(), history.summary.simulations + history.summary.simulations_discarded);
  EXPECT_GT(toy.expensive.calls(), 0);
  // Both models agree: every weight multiplier is exactly 1 and the posterior is exact.
  const auto& last = history.waves.back();
  for (const auto& p : last.particles) ASSERT_EQ(p.multiplier, 1.0);
  const auto exact = toy.ExactMarginals(toy.expensive);
  for (int k = 0; k < kBits; ++k) {
    EXPECT_NEAR(last.marginals_importance[k], exact[k], Bound(last, k)) << "bit " << k;
  }
}

// Records every callback's multi-fidelity state.
class FidelityLog : public SmcObserver {
 public:
  void OnWaveStart(const WaveRecord& w) override { starts.push_back(w.multi_fidelity); }
  void OnBatch(const BatchProgress& p, std::span<const Particle> /*accepted*/) override {
    batches.push_back(p.fidelity);
  }
  void OnWaveEnd(const WaveRecord& w) override { ends.push_back(w.multi_fidelity); }
  std::vector<std::optional<WaveFidelity>> starts, batches, ends;
};

TEST(MultiFidelity, MeasuredCostsAndTheCallbacksState) {
  Toy toy;
  const ToySimulator cheap({2, 5}, 0.3);
  SmcProblem problem{&toy.space, &toy.expensive, &toy.dist};
  problem.low_fidelity = &cheap;
  auto options = toy.Options(1.0, 0.1, 2);
  options.multi_fidelity.cost_ratio = 0.0;  // measured
  options.accepted_per_wave = 500;
  options.batch_size = 128;
  FidelityLog log;
  const auto history = RunCombinatorialSmc(problem, options, &log);
  ASSERT_EQ(log.starts.size(), history.waves.size());
  ASSERT_GT(log.batches.size(), history.waves.size());
  for (const auto& f : log.starts) {
    ASSERT_TRUE(f.has_value());
    EXPECT_EQ(f->expensive_simulations, 0);
    EXPECT_EQ(f->cheap_seconds, 0.0);
  }
  for (const auto& f : log.batches) ASSERT_TRUE(f.has_value());
  for (std::size_t t = 0; t < history.waves.size(); ++t) {
    const auto& f = *history.waves[t].multi_fidelity;
    EXPECT_EQ(f.continue_if_accepted, log.starts[t]->continue_if_accepted);
    EXPECT_GT(f.cheap_seconds, 0.0);
    EXPECT_GT(f.expensive_simulations, 0);
    EXPECT_GT(f.expensive_seconds, 0.0);
    // Both models are the same code: the measured ratio is of order 1 (loose: a shared machine).
    EXPECT_GT(f.cost_ratio, 0.01) << "wave " << t;
    EXPECT_LT(f.cost_ratio, 100.0) << "wave " << t;
    if (t + 1 < history.waves.size()) {
      const auto& next = *history.waves[t + 1].multi_fidelity;
      EXPECT_EQ(next.continue_if_accepted, f.next_continue_if_accepted);
      EXPECT_EQ(next.continue_if_rejected, f.next_continue_if_rejected);
    }
  }
  EXPECT_EQ(log.batches.back()->expensive_simulations,
            history.waves.back().multi_fidelity->expensive_simulations);
}

// y = w.b + theta + N(0, 0.3^2) (expensive), b 3 bits, theta ~ U(-2, 2); the cheap model drops
// bit 1, is shifted by 0.2 and has no noise.
class LinearSimulator : public Simulator {
 public:
  LinearSimulator(std::vector<double> w, double shift, double sigma)
      : w_(std::move(w)), shift_(shift), sigma_(sigma) {}
  int output_size() const override { return 1; }
  void Simulate(const ParameterView& theta,
                RandomStream& rng,
                std::span<double> out) const override {
    double y = theta.reals[0] + shift_ + (sigma_ > 0.0 ? sigma_ * rng.Normal() : 0.0);
    for (std::size_t k = 0; k < w_.size(); ++k) y += w_[k] * theta.bits[k];
    out[0] = y;
  }

 private:
  std::vector<double> w_;
  double shift_;
  double sigma_;
};

class AbsoluteDistance : public Distance {
 public:
  std::vector<DistanceComponent> components() const override {
    return {{"abs", ComponentKind::kThreshold, 1.0}};
  }
  void Evaluate(std::span<const double> y, std::span<double> out) const override {
    out[0] = std::abs(y[0] - 1.7);
  }
};

double Phi(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }

TEST(MultiFidelity, MixedBitsAndRealMatchEnumerationTimesQuadrature) {
  ContinuousPrior prior;
  prior.kind = PriorKind::kUniform;
  prior.low = -2.0;
  prior.high = 2.0;
  const std::vector<double> w = {1.0, -0.5, 2.0};
  const std::vector<double> bit_prior = {0.5, 0.3, 0.6};
  constexpr double kSigma = 0.3;
  constexpr double kEps = 0.25;
  BinarySpaceOptions so;
  so.dimension = 3;
  so.prior_one = bit_prior;
  const ParameterSpace space(BinarySpace(so), {{"theta", prior}});
  const LinearSimulator expensive(w, 0.0, kSigma);
  const LinearSimulator cheap({1.0, 0.0, 2.0}, 0.2, 0.0);
  const AbsoluteDistance dist;
  // The expensive model's exact ABC posterior: sum over b, midpoint rule over theta, of
  // p(b) p(theta) P(|y* - 1.7| <= eps | b, theta).
  std::vector<double> bit_mean(3, 0.0);
  double z = 0.0, m1 = 0.0, m2 = 0.0;
  constexpr int kSteps = 4000;
  for (int c = 0; c < 8; ++c) {
    double pb = 1.0, shift = 0.0;
    for (int k = 0; k < 3; ++k) {
      const bool one = ((c >> k) & 1) != 0;
      pb *= one ? bit_prior[k] : 1.0 - bit_prior[k];
      shift += one ? w[k] : 0.0;
    }
    for (int i = 0; i < kSteps; ++i) {
      const double t = -2.0 + (i + 0.5) * 4.0 / kSteps;
      const double m = shift + t;
      const double f = pb * (Phi((1.7 + kEps - m) / kSigma) - Phi((1.7 - kEps - m) / kSigma));
      z += f;
      m1 += f * t;
      m2 += f * t * t;
      for (int k = 0; k < 3; ++k) bit_mean[k] += ((c >> k) & 1) * f;
    }
  }
  for (auto& x : bit_mean) x /= z;
  const double mean = m1 / z;
  const double var = m2 / z - mean * mean;
  for (const auto binary : {BinaryKernelKind::kIndependent, BinaryKernelKind::kLogistic}) {
    SmcOptions o;
    o.num_waves = 4;
    o.accepted_per_wave = 3000;
    o.seed = 32;
    o.threads = 2;
    o.proposal.binary = binary;
    ThresholdSchedule s;
    s.kind = ThresholdKind::kList;
    s.values = {2.0, 1.0, 0.5, kEps};
    o.thresholds = {s};
    o.multi_fidelity.cost_ratio = 20.0;
    SmcProblem problem{&space, &expensive, &dist};
    problem.low_fidelity = &cheap;
    const auto h = RunCombinatorialSmc(problem, o);
    ASSERT_EQ(h.summary.termination, Termination::kTargetReached);
    const auto& last = h.waves.back();
    std::printf("%s: theta mean %.4f (exact %.4f), var %.4f (exact %.4f), ESS %.0f\n",
                ToString(binary),
                last.reals_mean[0],
                mean,
                last.reals_sd[0] * last.reals_sd[0],
                var,
                last.ess);
    ASSERT_GT(last.ess, 200.0);
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(last.marginals_importance[k], bit_mean[k], Bound(last, k)) << "bit " << k;
    }
    EXPECT_NEAR(
        last.reals_mean[0], mean, Bound(last, [](const Particle& p) { return p.theta.reals[0]; }));
    EXPECT_NEAR(last.reals_sd[0] * last.reals_sd[0], var, Bound(last, [&](const Particle& p) {
                  return (p.theta.reals[0] - mean) * (p.theta.reals[0] - mean);
                }));
  }
}

// The mixed bits x real toy above, small: the same history for one and two threads. This is the
// ThreadSanitizer's run of multi-fidelity with reals (CMakeLists.txt): the exactness test itself
// (2 x 4 waves of 3,000) took 98 s there and tests nothing more about threads.
TEST(MultiFidelity, MixedBitsAndRealSameHistoryForOneAndTwoThreads) {
  ContinuousPrior prior;
  prior.kind = PriorKind::kUniform;
  prior.low = -2.0;
  prior.high = 2.0;
  BinarySpaceOptions so;
  so.dimension = 3;
  so.prior_one = {0.5, 0.3, 0.6};
  const ParameterSpace space(BinarySpace(so), {{"theta", prior}});
  const LinearSimulator expensive({1.0, -0.5, 2.0}, 0.0, 0.3);
  const LinearSimulator cheap({1.0, 0.0, 2.0}, 0.2, 0.0);
  const AbsoluteDistance dist;
  for (const auto binary : {BinaryKernelKind::kIndependent, BinaryKernelKind::kLogistic}) {
    SmcOptions o;
    o.num_waves = 4;
    o.accepted_per_wave = 200;
    o.seed = 32;
    o.threads = 1;
    o.proposal.binary = binary;
    ThresholdSchedule s;
    s.kind = ThresholdKind::kList;
    s.values = {2.0, 1.0, 0.5, 0.25};
    o.thresholds = {s};
    o.multi_fidelity.cost_ratio = 20.0;
    SmcProblem problem{&space, &expensive, &dist};
    problem.low_fidelity = &cheap;
    const auto one = RunCombinatorialSmc(problem, o);
    ASSERT_EQ(one.summary.termination, Termination::kTargetReached) << ToString(binary);
    o.threads = 2;
    const auto two = RunCombinatorialSmc(problem, o);
    std::string where;
    EXPECT_TRUE(SameHistory(one, two, &where)) << ToString(binary) << ": " << where;
  }
}

TEST(MultiFidelity, SameHistoryForOneAndTwoThreads) {
  Toy toy;
  const ToySimulator cheap({2, 5}, 0.3, 0.1);
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
  // Tuned: some wave continues with other probabilities than the first.
  EXPECT_NE(one.waves.back().multi_fidelity->continue_if_rejected, 0.3);
}

using testing::Checkpoints;

TEST(MultiFidelity, ResumingFromAnyCheckpointReproducesTheUninterruptedRun) {
  Toy toy;
  const ToySimulator cheap({2, 5}, 0.3, 0.1);
  SmcProblem problem{&toy.space, &toy.expensive, &toy.dist};
  problem.low_fidelity = &cheap;
  auto options = toy.Options(0.5, 0.3, 2);
  options.accepted_per_wave = 300;
  options.batch_size = 128;
  Checkpoints checkpoints;
  const auto reference = RunCombinatorialSmc(problem, options, &checkpoints);
  ASSERT_GT(checkpoints.points.size(), 8U);
  int partial = 0;
  int between = 0;
  for (std::size_t i = 0; i < checkpoints.points.size(); ++i) {
    const auto& point = checkpoints.points[i];
    if (point.has_partial && i % 3 != 0) continue;  // every wave boundary, a third of the rest
    (point.has_partial ? partial : between) += 1;
    auto resumed_options = options;
    resumed_options.threads = 1 + static_cast<int>(i % 2);
    const auto resumed = RunCombinatorialSmc(problem, resumed_options, nullptr, &point);
    std::string where;
    EXPECT_TRUE(SameHistory(reference, resumed, &where)) << "checkpoint " << i << ": " << where;
  }
  EXPECT_GT(partial, 2);
  EXPECT_GT(between, 2);
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
  for (double floor : {0.0, 1.5}) {
    SmcOptions f;
    f.multi_fidelity.floor = floor;
    EXPECT_FALSE(f.IsValid(&why)) << floor;
    EXPECT_NE(why.find("SmcOptions::multi_fidelity.floor"), std::string::npos) << why;
  }
  for (double ratio : {-1.0, std::numeric_limits<double>::infinity()}) {
    SmcOptions f;
    f.multi_fidelity.cost_ratio = ratio;
    EXPECT_FALSE(f.IsValid(&why)) << ratio;
    EXPECT_NE(why.find("SmcOptions::multi_fidelity.cost_ratio"), std::string::npos) << why;
  }
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
