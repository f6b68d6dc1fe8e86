// Resample-move waves (SamplerMethod::kResampleMove, docs/algorithm.md "Resample-move") against
// exact posteriors: the coupled-bit problems of kernel_exactness_test.cpp (enumerated), the
// noise-aware linear problem of noise_aware_test.cpp (enumerated likelihood posterior), and the
// mixed minor-modes problem (enumeration x quadrature). The last wave's marginals must be within
// 5 Monte-Carlo standard errors of the exact ones, the errors being the run's own (clustered by
// ancestor: moved particles of one ancestor are correlated). Fixed seeds: deterministic.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <tuple>

#include "combabc/samplers/combinatorial_smc.hpp"
#include "combabc/samplers/monte_carlo_error.hpp"
#include "correlated_models.hpp"
#include "minor_modes.hpp"
#include "toy_models.hpp"

namespace combabc {
namespace {

SmcOptions MovingOptions(std::vector<double> thresholds, int n, std::uint64_t seed) {
  SmcOptions o;
  o.method = SamplerMethod::kResampleMove;
  // The moved waves' own exactness and errors: the run ends on its last move wave.
  o.moves.final_wave = FinalWave::kNever;
  o.num_waves = 30;
  o.accepted_per_wave = n;
  o.seed = seed;
  o.threads = 2;
  ThresholdSchedule s;
  s.target = thresholds.back();
  o.thresholds = {s};
  return o;
}

// The last wave's bit marginals within 5 of its own standard errors (plus a small floor for an
// exact 0 or 1) of `exact`.
void PrintWaves(const RunHistory& h) {
  for (const auto& w : h.waves) {
    std::printf("  wave %d eps %.4g candidates %lld rate %.3f",
                w.wave + 1,
                w.thresholds.at(0),
                static_cast<long long>(w.candidates),
                w.acceptance_rate);
    if (w.moves) {
      std::printf(" step %.3f survivors %.1f rounds %d indep %lld/%lld",
                  w.moves->step,
                  w.moves->survivor_ess,
                  w.moves->rounds,
                  static_cast<long long>(w.moves->independent_accepted),
                  static_cast<long long>(w.moves->independent_proposed));
    }
    std::printf("\n");
  }
}

void ExpectMarginals(const RunHistory& h, const std::vector<double>& exact, const char* name) {
  const auto& last = h.waves.back();
  const WaveErrors errors = WaveMonteCarloErrors(last);
  ASSERT_TRUE(last.moves.has_value()) << name << ": the last wave was not a move wave";
  std::printf("%s: %zu waves, %lld simulations, last wave %d rounds, %.0f%% accepted\n",
              name,
              h.waves.size(),
              static_cast<long long>(h.summary.simulations),
              last.moves->rounds,
              100.0 * last.acceptance_rate);
  for (std::size_t k = 0; k < exact.size(); ++k) {
    const auto& m = errors.bits[k];
    std::printf("  bit %2zu exact %.4f got %.4f se %.4f\n", k, exact[k], m.value, m.se);
    EXPECT_NEAR(m.value, exact[k], 5.0 * m.se + 2e-3) << name << ", bit " << k;
  }
}

TEST(MoveExactness, ConfigurationAndItsComplement) {
  const std::vector<std::uint8_t> pattern = {1, 0, 0, 1, 1, 1, 0, 1, 0, 0, 1, 0, 1, 1, 0, 0};
  const testing::ComplementDistance distance(pattern);
  const std::vector<double> prior(16, 0.5);
  const ParameterSpace space{BinarySpace::Independent(16)};
  const testing::IdentitySimulator sim(16);
  const auto h = RunCombinatorialSmc({&space, &sim, &distance}, MovingOptions({1}, 500, 21));
  PrintWaves(h);
  ASSERT_EQ(h.summary.termination, Termination::kTargetReached);
  const auto exact = testing::ExactMoments(distance, prior, 1.0).mean;
  ExpectMarginals(h, exact, "complement d=16");
}

TEST(MoveExactness, ChainCoupledBits) {
  const testing::ChainDistance distance;
  const std::vector<double> prior = {0.5, 0.4, 0.6, 0.5, 0.5, 0.3, 0.5, 0.7, 0.5, 0.5, 0.45, 0.5};
  BinarySpaceOptions so;
  so.dimension = 12;
  so.prior_one = prior;
  const ParameterSpace space{BinarySpace(so)};
  const testing::IdentitySimulator sim(12);
  const auto h = RunCombinatorialSmc({&space, &sim, &distance}, MovingOptions({1.5}, 500, 22));
  PrintWaves(h);
  ASSERT_EQ(h.summary.termination, Termination::kTargetReached);
  const auto exact = testing::ExactMoments(distance, prior, 1.5).mean;
  ExpectMarginals(h, exact, "chain d=12");
}

// The noise-aware linear problem of noise_aware_test.cpp: temperatures down to 1, where the target
// is p(theta) exp(-d(theta)), enumerated over 256 configurations.
TEST(MoveExactness, NoiseAwareLikelihoodPosterior) {
  const std::vector<double> prior = {0.5, 0.3, 0.6, 0.5, 0.4, 0.7, 0.5, 0.2};
  const testing::LinearSimulator sim{{{1.0, 0.5, 0.0, 0.1, 0.0, 0.0, 0.0, 0.0},
                                      {0.0, 1.0, 0.8, 0.0, 0.2, 0.0, 0.0, 0.0},
                                      {0.3, 0.0, 1.0, 0.1, 0.0, 0.6, 0.0, 0.0},
                                      {0.0, 0.0, 0.0, 0.1, 1.0, 0.4, 0.0, 0.0},
                                      {0.5, 0.0, 0.0, 0.0, 0.0, 1.0, 0.2, 0.0},
                                      {0.0, 0.2, 0.0, 0.0, 0.0, 0.0, 0.7, 0.7}}};
  const testing::GaussianNllDistance dist{{1.25, 0.7, 1.3, 0.2, 0.75, 0.6}, 0.3};
  BinarySpaceOptions so;
  so.dimension = 8;
  so.prior_one = prior;
  const ParameterSpace space{BinarySpace(so)};
  std::vector<double> exact(8, 0.0);
  double z = 0.0;
  std::vector<double> y(6);
  double d = 0.0;
  RandomStream rng(0, 0, 0);
  for (int c = 0; c < 256; ++c) {
    std::vector<std::uint8_t> bits(8);
    double p = 1.0;
    for (int k = 0; k < 8; ++k) {
      bits[k] = (c >> k) & 1;
      p *= bits[k] != 0 ? prior[k] : 1.0 - prior[k];
    }
    sim.Simulate(ParameterView{bits, {}}, rng, y);
    dist.Evaluate(y, std::span(&d, 1));
    p *= std::exp(-d);
    z += p;
    for (int k = 0; k < 8; ++k) exact[k] += bits[k] * p;
  }
  for (auto& x : exact) x /= z;
  const auto h = RunCombinatorialSmc({&space, &sim, &dist}, MovingOptions({1.0}, 1000, 2013));
  PrintWaves(h);
  ASSERT_EQ(h.summary.termination, Termination::kTargetReached);
  ASSERT_EQ(h.waves.back().thresholds[0], 1.0);
  ExpectMarginals(h, exact, "noise-aware d=8");

  // With the final independent wave (MoveOptions::final_wave, kAuto): one rejection wave at T = 1
  // after the last move wave, proposing from the ancestor kernel fitted to the moved particles.
  // Its draws are independent given those: its errors are the delta method's without clusters.
  // Its weights stay nearly even (ESS 737-951 of 1000 when measured); here the moved wave's
  // clustered ESS is as large (few resamplings), on the sensor-design example it is far smaller.
  auto o = MovingOptions({1.0}, 1000, 2013);
  o.moves.final_wave = FinalWave::kAuto;
  const auto f = RunCombinatorialSmc({&space, &sim, &dist}, o);
  ASSERT_EQ(f.summary.termination, Termination::kTargetReached);
  ASSERT_EQ(f.waves.size(), h.waves.size() + 1);
  const WaveRecord& last = f.waves.back();
  const WaveRecord& moved = f.waves[f.waves.size() - 2];
  ASSERT_FALSE(last.moves.has_value());
  EXPECT_EQ(last.thresholds, moved.thresholds);
  EXPECT_TRUE(AncestorClusters(last, true).empty());
  const WaveErrors errors = WaveMonteCarloErrors(last);
  const WaveErrors moved_errors = WaveMonteCarloErrors(moved);
  for (std::size_t k = 0; k < exact.size(); ++k) {
    const auto& m = errors.bits[k];
    std::printf("  final wave: bit %zu exact %.4f got %.4f se %.4f ess %.0f (moved wave %.0f)\n",
                k,
                exact[k],
                m.value,
                m.se,
                m.ess,
                moved_errors.bits[k].ess);
    EXPECT_NEAR(m.value, exact[k], 5.0 * m.se + 2e-3) << "final wave, bit " << k;
    EXPECT_GT(m.ess, 500.0) << "final wave, bit " << k;
  }
}

// The linear problem's six outputs as two experiments, each a Gaussian likelihood component (the
// first three outputs, the last three).
class TwoExperimentNll : public Distance {
 public:
  TwoExperimentNll(std::vector<double> observed, double sigma, int components)
      : observed_(std::move(observed)), sigma_(sigma), components_(components) {}
  std::vector<DistanceComponent> components() const override {
    std::vector<DistanceComponent> c = {{"a", ComponentKind::kNegLogLikelihood, 1.0}};
    if (components_ == 2) c.push_back({"b", ComponentKind::kNegLogLikelihood, 1.0});
    return c;
  }
  void Evaluate(std::span<const double> y, std::span<double> out) const override {
    double a = 0.0;
    double b = 0.0;
    for (std::size_t j = 0; j < observed_.size(); ++j) {
      const double r = (y[j] - observed_[j]) / sigma_;
      (j < 3 ? a : b) += 0.5 * r * r;
    }
    out[0] = a;
    if (components_ == 2) out[1] = b;
  }

 private:
  std::vector<double> observed_;
  double sigma_;
  int components_;
};

// Adding data to a finished run (SmcProblem::start; docs/algorithm.md, "Adding data to a finished
// run"): the first experiment's posterior, re-simulated with both experiments, brought to the
// joint posterior by resample-move waves, equals the enumerated joint posterior; and it costs
// fewer simulations than the joint calibration from the prior.
TEST(MoveExactness, AddingAnExperimentToAFinishedRun) {
  const std::vector<double> prior = {0.5, 0.3, 0.6, 0.5, 0.4, 0.7, 0.5, 0.2};
  const testing::LinearSimulator sim{{{1.0, 0.5, 0.0, 0.1, 0.0, 0.0, 0.0, 0.0},
                                      {0.0, 1.0, 0.8, 0.0, 0.2, 0.0, 0.0, 0.0},
                                      {0.3, 0.0, 1.0, 0.1, 0.0, 0.6, 0.0, 0.0},
                                      {0.0, 0.0, 0.0, 0.1, 1.0, 0.4, 0.0, 0.0},
                                      {0.5, 0.0, 0.0, 0.0, 0.0, 1.0, 0.2, 0.0},
                                      {0.0, 0.2, 0.0, 0.0, 0.0, 0.0, 0.7, 0.7}}};
  const std::vector<double> observed = {1.25, 0.7, 1.3, 0.2, 0.75, 0.6};
  const TwoExperimentNll first(observed, 0.3, 1);
  const TwoExperimentNll both(observed, 0.3, 2);
  BinarySpaceOptions so;
  so.dimension = 8;
  so.prior_one = prior;
  const ParameterSpace space{BinarySpace(so)};
  std::vector<double> exact(8, 0.0);
  double z = 0.0;
  std::vector<double> y(6);
  std::vector<double> d(2);
  RandomStream rng(0, 0, 0);
  for (int c = 0; c < 256; ++c) {
    std::vector<std::uint8_t> bits(8);
    double p = 1.0;
    for (int k = 0; k < 8; ++k) {
      bits[k] = (c >> k) & 1;
      p *= bits[k] != 0 ? prior[k] : 1.0 - prior[k];
    }
    sim.Simulate(ParameterView{bits, {}}, rng, y);
    both.Evaluate(y, d);
    p *= std::exp(-d[0] - d[1]);
    z += p;
    for (int k = 0; k < 8; ++k) exact[k] += bits[k] * p;
  }
  for (auto& x : exact) x /= z;
  auto o = MovingOptions({1.0}, 1000, 2002);
  const auto finished = RunCombinatorialSmc({&space, &sim, &first}, o);
  ASSERT_EQ(finished.summary.termination, Termination::kTargetReached);
  StartPopulation start;
  for (const auto& p : finished.waves.back().particles) {
    start.thetas.push_back(p.theta);
    start.weights.push_back(p.weight);
  }
  start.thresholds = {1.0, std::numeric_limits<double>::infinity()};
  ThresholdSchedule s;
  s.target = 1.0;
  o.thresholds = {s, s};
  SmcProblem added{&space, &sim, &both};
  added.start = &start;
  const auto h = RunCombinatorialSmc(added, o);
  PrintWaves(h);
  ASSERT_EQ(h.summary.termination, Termination::kTargetReached);
  EXPECT_EQ(h.waves.front().candidates, 1000);  // wave 0: the finished posterior, re-simulated
  ExpectMarginals(h, exact, "added experiment d=8");
  const auto from_prior = RunCombinatorialSmc({&space, &sim, &both}, o);
  std::printf("from the finished run: %lld simulations; from the prior: %lld\n",
              static_cast<long long>(h.summary.simulations),
              static_cast<long long>(from_prior.summary.simulations));
  EXPECT_LT(h.summary.simulations, from_prior.summary.simulations);
}

// The mixed minor-modes problem (bits and a real; minor_modes.hpp) with local and independent
// moves: the bit marginals, the real's mean and both minor modes' masses.
TEST(MoveExactness, MixedMinorModes) {
  namespace mm = testing::minor_modes;
  for (const auto variant : {mm::Variant::kSingleFlips, mm::Variant::kJointFlips}) {
    const ParameterSpace space = mm::Space();
    const mm::Simulator sim(variant);
    const mm::Distance dist;
    const mm::Exact exact = mm::ExactPosterior(variant);
    auto o = mm::Options(BinaryKernelKind::kIndependent, ContinuousKernelKind::kNormal, 1000, 2301);
    o.method = SamplerMethod::kResampleMove;
    // The problem's list schedule, whose steps keep enough of the ESS as they are.
    o.moves.ess_fraction = 0.1;
    const auto h = RunCombinatorialSmc({&space, &sim, &dist}, o);
    PrintWaves(h);
    ASSERT_EQ(h.summary.termination, Termination::kTargetReached) << mm::Name(variant);
    ExpectMarginals(h, exact.bit_mean, mm::Name(variant));
    const auto& last = h.waves.back();
    const WaveErrors errors = WaveMonteCarloErrors(last);
    EXPECT_NEAR(errors.real_means[0].value, exact.mean, 5.0 * errors.real_means[0].se + 2e-3)
        << mm::Name(variant);
    // Both minor modes' masses within 5 of their errors (clustered by parent and by Eve, as the
    // run's own errors are): the modes are kept, and where the moves rarely jump between them
    // (the joint-flips variant: three bits and the real together) the errors say so.
    std::vector<double> weights;
    std::vector<double> plus;
    std::vector<double> minus;
    for (const auto& p : last.particles) {
      const int mode = mm::MinorMode(variant, p.theta.bits);
      weights.push_back(p.weight);
      plus.push_back(mode == 1 ? 1.0 : 0.0);
      minus.push_back(mode == -1 ? 1.0 : 0.0);
    }
    const auto parents = AncestorClusters(last, false);
    const auto eves = AncestorClusters(last, true);
    for (const auto& [name, indicator, truth] :
         {std::tuple{"+", &plus, exact.minor_plus}, std::tuple{"-", &minus, exact.minor_minus}}) {
      const auto by_parent = WeightedMean(weights, *indicator, parents);
      const auto by_eve = WeightedMean(weights, *indicator, eves);
      const double se = std::max(by_parent.se, by_eve.se);
      std::printf("  minor mode %s: %.4f se %.4f (exact %.4f)\n", name, by_parent.value, se, truth);
      EXPECT_GT(by_parent.value, 0.0) << mm::Name(variant) << ": minor mode " << name << " lost";
      EXPECT_NEAR(by_parent.value, truth, 5.0 * se + 2e-3) << mm::Name(variant) << " " << name;
    }
  }
}

// MoveOptions::final_wave on the chain problem, whose moves are accepted at 0.005: a final
// independent wave would cost more than the run, and kAuto leaves it out; kAlways draws it.
TEST(MoveExactness, FinalWaveTooDearIsLeftOut) {
  const testing::ChainDistance chain;
  const ParameterSpace space{BinarySpace::Independent(12)};
  const testing::IdentitySimulator sim(12);
  auto c = MovingOptions({1.5}, 100, 22);
  c.moves.final_wave = FinalWave::kAuto;
  const auto skipped = RunCombinatorialSmc({&space, &sim, &chain}, c);
  ASSERT_EQ(skipped.summary.termination, Termination::kTargetReached);
  EXPECT_TRUE(skipped.waves.back().moves.has_value());
  c.moves.final_wave = FinalWave::kAlways;
  const auto drawn = RunCombinatorialSmc({&space, &sim, &chain}, c);
  ASSERT_EQ(drawn.waves.size(), skipped.waves.size() + 1);
  EXPECT_FALSE(drawn.waves.back().moves.has_value());
  EXPECT_EQ(drawn.waves.back().thresholds, skipped.waves.back().thresholds);
}

// The errors' coverage over seeds (docs/benchmarks.md, "Monte-Carlo error coverage"): the mean of
// z^2 over 20 seeds and every bit, which is 1 for honest errors. A measurement, run by hand:
//   samplers_move_exactness_test --gtest_also_run_disabled_tests --gtest_filter=*Coverage*
TEST(MoveExactness, DISABLED_CoverageOverSeeds) {
  const testing::ChainDistance chain;
  const std::vector<std::uint8_t> pattern = {1, 0, 0, 1, 1, 1, 0, 1, 0, 0, 1, 0, 1, 1, 0, 0};
  const testing::ComplementDistance complement(pattern);
  const std::vector<double> chain_prior = {
      0.5, 0.4, 0.6, 0.5, 0.5, 0.3, 0.5, 0.7, 0.5, 0.5, 0.45, 0.5};
  for (int problem = 0; problem < 4; ++problem) {
    // Problems 2 and 3: 0 and 1 again, ending with a final independent wave.
    const bool final_wave = problem >= 2;
    const Distance& distance = problem % 2 == 0 ? static_cast<const Distance&>(chain) : complement;
    const std::vector<double> prior = problem % 2 == 0 ? chain_prior : std::vector<double>(16, 0.5);
    const double eps = problem % 2 == 0 ? 1.5 : 1.0;
    BinarySpaceOptions so;
    so.dimension = static_cast<int>(prior.size());
    so.prior_one = prior;
    const ParameterSpace space{BinarySpace(so)};
    const testing::IdentitySimulator sim(so.dimension);
    const auto exact = testing::ExactMoments(distance, prior, eps).mean;
    double parent_z2 = 0.0;
    double z2 = 0.0;
    int n = 0;
    for (std::uint64_t seed = 1; seed <= 20; ++seed) {
      auto o = MovingOptions({eps}, 500, seed);
      o.moves.final_wave = final_wave ? FinalWave::kAlways : FinalWave::kNever;
      const auto h = RunCombinatorialSmc({&space, &sim, &distance}, o);
      const auto& last = h.waves.back();
      const WaveErrors errors = WaveMonteCarloErrors(last);
      const auto parents = AncestorClusters(last, false);
      std::vector<double> weights;
      for (const auto& p : last.particles) weights.push_back(p.weight);
      for (std::size_t k = 0; k < exact.size(); ++k) {
        std::vector<double> values;
        for (const auto& p : last.particles) values.push_back(p.theta.bits[k]);
        const double se_parent =
            parents.empty() ? errors.bits[k].se : WeightedMean(weights, values, parents).se;
        const double z = (errors.bits[k].value - exact[k]) / errors.bits[k].se;
        const double zp = (errors.bits[k].value - exact[k]) / se_parent;
        z2 += z * z;
        parent_z2 += zp * zp;
        ++n;
      }
    }
    std::printf("%s%s: mean z^2 %.2f (parent clusters alone %.2f) over %d estimates\n",
                problem % 2 == 0 ? "chain d=12" : "complement d=16",
                final_wave ? ", final independent wave" : "",
                z2 / n,
                parent_z2 / n,
                n);
  }
}

}  // namespace
}  // namespace combabc
