// Exact enumeration (samplers/enumeration.hpp): its posterior against a brute force written here
// independently, ties, indicator components, thread-count independence, limits and interruption.
#include "combabc/samplers/enumeration.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "combabc/core/error.hpp"
#include "toy_models.hpp"

namespace combabc {
namespace {

constexpr int kBits = 10;
constexpr double kEps = 3.0;

struct Toy {
  std::vector<double> prior = {0.5, 0.3, 0.6, 0.5, 0.4, 0.7, 0.5, 0.2, 0.9, 0.35};
  // Bit 0 weighs 4 > eps: always 1 under the posterior (a constant bit). Bits 1 and 2 interact
  // through the coupling term.
  testing::WeightedL1Distance dist{
      {1, 0, 1, 1, 0, 0, 1, 0, 1, 1}, {4, 2, 2, 2, 1.5, 1.5, 1, 1, 1, 0.5}, 1, 2, 1.0};
  testing::IdentitySimulator sim{kBits};
  ParameterSpace space = [this] {
    BinarySpaceOptions o;
    o.dimension = kBits;
    o.prior_one = prior;
    return ParameterSpace(BinarySpace(o));
  }();
  SmcProblem problem() const { return {&space, &sim, &dist}; }
};

EnumerationOptions Options(int threads) {
  EnumerationOptions o;
  o.thresholds = {kEps};
  o.threads = threads;
  o.batch_size = 100;  // several batches, the last one short
  o.top = 5;
  return o;
}

TEST(Enumeration, MatchesBruteForcePosterior) {
  Toy t;
  // Brute force: mass, first and second moments of every configuration.
  double z = 0.0, z_all = 0.0;
  std::vector<double> m(kBits, 0.0), mm(static_cast<std::size_t>(kBits) * kBits, 0.0);
  std::int64_t accepted = 0;
  std::vector<double> y(kBits);
  for (int c = 0; c < (1 << kBits); ++c) {
    double p = 1.0;
    for (int k = 0; k < kBits; ++k) {
      y[k] = (c >> k) & 1;
      p *= y[k] != 0.0 ? t.prior[k] : 1.0 - t.prior[k];
    }
    z_all += p;
    double d = 0.0;
    t.dist.Evaluate(y, std::span(&d, 1));
    if (d > kEps) continue;
    ++accepted;
    z += p;
    for (int i = 0; i < kBits; ++i) {
      m[i] += p * y[i];
      for (int j = 0; j < kBits; ++j) mm[i * kBits + j] += p * y[i] * y[j];
    }
  }
  ASSERT_NEAR(z_all, 1.0, 1e-12);
  const auto r = Enumerate(t.problem(), Options(1));
  EXPECT_EQ(r.configurations, 1024);
  EXPECT_EQ(r.enumerated, 1024);
  EXPECT_EQ(r.accepted, accepted);
  EXPECT_FALSE(r.interrupted);
  EXPECT_NEAR(r.evidence, z, 1e-14);
  ASSERT_EQ(r.marginals.size(), static_cast<std::size_t>(kBits));
  ASSERT_EQ(r.correlations.size(), static_cast<std::size_t>(kBits * kBits));
  EXPECT_DOUBLE_EQ(r.marginals[0], 1.0);
  for (int i = 0; i < kBits; ++i) {
    EXPECT_NEAR(r.marginals[i], m[i] / z, 1e-12) << "bit " << i;
    for (int j = 0; j < kBits; ++j) {
      const double mi = m[i] / z, mj = m[j] / z;
      const double var = mi * (1 - mi) * mj * (1 - mj);
      const double want = var > 1e-12 ? (mm[i * kBits + j] / z - mi * mj) / std::sqrt(var) : 0.0;
      EXPECT_NEAR(r.correlations[i * kBits + j], want, 1e-9) << i << "," << j;
    }
  }
  EXPECT_EQ(r.correlations[0], 0.0);  // constant bit: 0, not NaN, also on the diagonal
  EXPECT_EQ(r.correlations[1 * kBits + 1], 1.0);
  // The threshold and the coupling make bits 1 and 2 dependent: the comparison above is not 0 = 0.
  EXPECT_GT(std::abs(r.correlations[1 * kBits + 2]), 0.01);
  // Every accepted configuration is kept, weights are the normalised masses.
  ASSERT_EQ(r.particles.size(), static_cast<std::size_t>(accepted));
  double sum = 0.0;
  for (std::size_t i = 0; i < r.particles.size(); ++i) {
    const Particle& p = r.particles[i];
    if (i > 0) {
      EXPECT_LT(r.particles[i - 1].index, p.index);
    }
    double mass = 1.0;
    for (int k = 0; k < kBits; ++k) {
      EXPECT_EQ(p.theta.bits[k], (p.index >> k) & 1);
      mass *= p.theta.bits[k] ? t.prior[k] : 1.0 - t.prior[k];
    }
    EXPECT_NEAR(p.weight, mass / z, 1e-12);
    EXPECT_LE(p.distance[0], kEps);
    EXPECT_EQ(p.output.size(), static_cast<std::size_t>(kBits));
    sum += p.weight;
  }
  EXPECT_NEAR(sum, 1.0, 1e-12);
  // The top configurations: largest mass first.
  ASSERT_EQ(r.top.size(), 5u);
  for (std::size_t i = 1; i < r.top.size(); ++i) {
    EXPECT_GE(r.top[i - 1].weight, r.top[i].weight);
  }
  for (const Particle& p : r.particles) EXPECT_LE(p.weight, r.top[0].weight + 1e-15);
  // The one-wave record the history stores.
  const WaveRecord w = r.Wave({kEps}, t.space.binary().free_prior_one());
  EXPECT_EQ(w.candidates, 1024);
  EXPECT_EQ(w.accepted, accepted);
  EXPECT_EQ(w.marginals_importance, r.marginals);
  EXPECT_EQ(w.marginals_paper, r.marginals);
  EXPECT_TRUE(w.complete);
  // Its pair correlations are its particles', by the same estimator; every accepted configuration
  // is kept here, so they are the exact ones to round-off.
  ASSERT_EQ(w.pair_correlations.size(), r.correlations.size());
  for (std::size_t k = 0; k < r.correlations.size(); ++k) {
    EXPECT_NEAR(w.pair_correlations[k], r.correlations[k], 1e-12) << k;
  }
}

// A noise-aware likelihood component at temperature T weighs each configuration by
// prior x exp(-d / T), computed without underflow when every d is large (here d >= 2000, whose
// exp(-d) is 0 in double precision).
TEST(Enumeration, LikelihoodComponentsWeighByExpMinusDOverT) {
  const std::vector<double> prior = {0.5, 0.3, 0.6, 0.5, 0.4, 0.7};
  BinarySpaceOptions so;
  so.dimension = 6;
  so.prior_one = prior;
  const ParameterSpace space{BinarySpace(so)};
  const testing::LinearSimulator sim{{{1.0, 0.5, 0.0, 0.1, 0.0, 0.0},
                                      {0.0, 1.0, 0.8, 0.0, 0.2, 0.0},
                                      {0.3, 0.0, 1.0, 0.1, 0.0, 0.6},
                                      {0.0, 0.0, 0.0, 0.1, 1.0, 0.4}}};
  for (const double offset : {0.0, 2000.0}) {
    // d = sum (y - observed)^2 / (2 sigma^2) + offset.
    class Shifted : public Distance {
     public:
      explicit Shifted(double offset) : nll_({1.25, 0.7, 1.3, 0.2}, 0.3), offset_(offset) {}
      std::vector<DistanceComponent> components() const override { return nll_.components(); }
      void Evaluate(std::span<const double> y, std::span<double> out) const override {
        nll_.Evaluate(y, out);
        out[0] += offset_;
      }

     private:
      testing::GaussianNllDistance nll_;
      double offset_;
    };
    const Shifted dist(offset);
    for (const double temperature : {1.0, 3.0}) {
      EnumerationOptions o;
      o.thresholds = {temperature};
      const auto r = Enumerate({&space, &sim, &dist}, o);
      std::vector<double> exact(6, 0.0);
      double z = 0.0;
      std::vector<double> y(4);
      double d = 0.0;
      RandomStream rng(0, 0, 0);
      for (int c = 0; c < 64; ++c) {
        std::vector<std::uint8_t> bits(6);
        double p = 1.0;
        for (int k = 0; k < 6; ++k) {
          bits[k] = (c >> k) & 1;
          p *= bits[k] != 0 ? prior[k] : 1.0 - prior[k];
        }
        sim.Simulate(ParameterView{bits, {}}, rng, y);
        dist.Evaluate(y, std::span(&d, 1));
        p *= std::exp(-(d - offset) / temperature);
        z += p;
        for (int k = 0; k < 6; ++k) exact[k] += bits[k] * p;
      }
      ASSERT_EQ(r.accepted, 64);
      ASSERT_EQ(r.marginals.size(), 6u);
      for (int k = 0; k < 6; ++k) {
        EXPECT_NEAR(r.marginals[k], exact[k] / z, 1e-12)
            << "offset " << offset << ", T " << temperature << ", bit " << k;
      }
      double weights = 0.0;
      for (const auto& p : r.particles) weights += p.weight;
      EXPECT_NEAR(weights, 1.0, 1e-12);
    }
  }
}

TEST(Enumeration, MaxParticlesKeepsTheLargestMasses) {
  Toy t;
  auto o = Options(1);
  const auto all = Enumerate(t.problem(), o);
  o.max_particles = 7;
  const auto some = Enumerate(t.problem(), o);
  ASSERT_EQ(some.particles.size(), 7u);
  EXPECT_EQ(some.accepted, all.accepted);
  EXPECT_EQ(some.marginals, all.marginals);  // exact whatever is kept
  double smallest_kept = 1.0;
  for (const Particle& p : some.particles) smallest_kept = std::min(smallest_kept, p.log_weight);
  int larger = 0;
  for (const Particle& p : all.particles) larger += p.log_weight > smallest_kept;
  EXPECT_LE(larger, 6);
}

TEST(Enumeration, ThreadCountDoesNotChangeAnything) {
  Toy t;
  const auto a = Enumerate(t.problem(), Options(1));
  const auto b = Enumerate(t.problem(), Options(4));
  EXPECT_EQ(a.accepted, b.accepted);
  EXPECT_EQ(a.evidence, b.evidence);    // bit for bit: exact comparison
  EXPECT_EQ(a.marginals, b.marginals);  // bit for bit: operator== on doubles
  EXPECT_EQ(a.correlations, b.correlations);
  EXPECT_EQ(a.ess, b.ess);
  ASSERT_EQ(a.particles.size(), b.particles.size());
  for (std::size_t i = 0; i < a.particles.size(); ++i) {
    EXPECT_EQ(a.particles[i].index, b.particles[i].index);
    EXPECT_EQ(a.particles[i].weight, b.particles[i].weight);
    EXPECT_EQ(a.particles[i].distance, b.particles[i].distance);
  }
}

TEST(Enumeration, TiedBitsEnumerateFreeParametersOnly) {
  constexpr int d = 8;
  BinarySpaceOptions o;
  o.dimension = d;
  o.tied = {{0, 4}, {1, 5}, {2, 6}};  // 3 groups + 2 untied bits = 5 free parameters
  const ParameterSpace space{BinarySpace(o)};
  testing::IdentitySimulator sim{d};
  testing::WeightedL1Distance dist{{1, 0, 1, 0, 1, 0, 1, 0}, std::vector<double>(d, 1.0)};
  EnumerationOptions options;
  options.thresholds = {1.0};
  const auto r = Enumerate({&space, &sim, &dist}, options);
  EXPECT_EQ(r.configurations, 32);
  // Exact target (distance 0) and the two untied bits flipped (distance 1 each); a tied group
  // flipped costs 2. Uniform prior over 32 configurations.
  EXPECT_EQ(r.accepted, 3);
  EXPECT_NEAR(r.evidence, 3.0 / 32, 1e-15);
  EXPECT_NEAR(r.marginals[0], 1.0, 1e-15);
  EXPECT_NEAR(r.marginals[3], 1.0 / 3, 1e-15);
  for (const Particle& p : r.particles) {
    for (int k = 0; k < 3; ++k) EXPECT_EQ(p.theta.bits[k], p.theta.bits[k + 4]);
  }
  // Tied bits are perfectly correlated wherever they vary; here they are constant: 0.
  EXPECT_EQ(r.correlations[0 * d + 4], 0.0);
  EXPECT_NEAR(r.correlations[3 * d + 7], -0.5, 1e-12);
}

TEST(Enumeration, IndicatorComponentsMustEqualRequired) {
  constexpr int d = 6;
  const ParameterSpace space{BinarySpace::Independent(d)};
  testing::IdentitySimulator sim{d};
  testing::SplitDistance dist{{0, 0, 0, 0, 0, 0}};
  EnumerationOptions options;
  options.thresholds = {1.0, 1.0};
  const auto r = Enumerate({&space, &sim, &dist}, options);
  // bit 0 must be set (indicator); left half {0,1,2} then has distance >= 1, so bits 1, 2 = 0;
  // right half {3,4,5} at most one bit set: 4 configurations.
  EXPECT_EQ(r.accepted, 4);
  EXPECT_EQ(r.marginals[0], 1.0);
  EXPECT_EQ(r.marginals[1], 0.0);
  EXPECT_NEAR(r.marginals[3], 0.25, 1e-15);
}

TEST(Enumeration, NothingAcceptedHasNoPosterior) {
  Toy t;
  auto o = Options(1);
  o.thresholds = {0.0};
  const auto r = Enumerate(t.problem(), o);
  EXPECT_EQ(r.accepted, 1);  // only the target itself, at distance exactly 0
  EXPECT_EQ(r.marginals[7], 0.0);
  testing::WeightedL1Distance far{std::vector<double>(kBits, 2.0), std::vector<double>(kBits, 1.0)};
  const auto none = Enumerate({&t.space, &t.sim, &far}, o);
  EXPECT_EQ(none.accepted, 0);
  EXPECT_EQ(none.evidence, 0.0);
  EXPECT_TRUE(none.marginals.empty());
  EXPECT_TRUE(none.correlations.empty());
  EXPECT_TRUE(none.particles.empty());
  EXPECT_TRUE(none.top.empty());
}

// A configuration of prior mass 0 (here bit 3, prior 0, set) has no posterior mass: it is not
// counted as accepted nor listed, and when only such configurations pass the thresholds there is
// no posterior (not weights divided by a zero evidence).
TEST(Enumeration, ConfigurationsOfPriorMassZeroAreNotAccepted) {
  constexpr int d = 4;
  BinarySpaceOptions o;
  o.dimension = d;
  o.prior_one = {0.5, 0.5, 0.5, 0.0};
  const ParameterSpace space{BinarySpace(o)};
  testing::IdentitySimulator sim{d};
  testing::WeightedL1Distance dist{{1, 0, 1, 0}, {1, 1, 1, 0.5}};
  EnumerationOptions options;
  options.thresholds = {0.5};
  options.top = 10;
  // Distance <= 0.5: the target 1010 and 1011 (bit 3 weighs 0.5); 1011 has prior 0.
  const auto r = Enumerate({&space, &sim, &dist}, options);
  EXPECT_EQ(r.configurations, 16);
  EXPECT_EQ(r.accepted, 1);
  EXPECT_NEAR(r.evidence, 0.125, 1e-15);
  ASSERT_EQ(r.top.size(), 1U);
  EXPECT_EQ(r.top[0].weight, 1.0);
  EXPECT_EQ(r.marginals[3], 0.0);
  // Only the prior-0 configuration 1011 within the thresholds: nothing accepted.
  testing::WeightedL1Distance only_zero{{1, 0, 1, 1}, {1, 1, 1, 0.5}};
  options.thresholds = {0.0};
  const auto none = Enumerate({&space, &sim, &only_zero}, options);
  EXPECT_EQ(none.accepted, 0);
  EXPECT_EQ(none.evidence, 0.0);
  EXPECT_TRUE(none.top.empty());
  EXPECT_TRUE(none.particles.empty());
}

std::string ErrorOf(const SmcProblem& problem, const EnumerationOptions& options) {
  try {
    Enumerate(problem, options);
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kConfig);
    return e.what();
  }
  return "";
}

TEST(Enumeration, RefusesWhatItCannotEnumerate) {
  testing::IdentitySimulator sim25{25};
  testing::WeightedL1Distance dist25{std::vector<double>(25, 0.0), std::vector<double>(25, 1.0)};
  const ParameterSpace big{BinarySpace::Independent(25)};
  EnumerationOptions o;
  o.thresholds = {1.0};
  EXPECT_NE(ErrorOf({&big, &sim25, &dist25}, o).find("2^25"), std::string::npos);

  const ParameterSpace mixed{BinarySpace::Independent(3),
                             {{"k", {.kind = PriorKind::kUniform, .low = 0.0, .high = 1.0}}}};
  testing::IdentitySimulator sim3{3};
  testing::WeightedL1Distance dist3{{0, 0, 0}, {1, 1, 1}};
  EXPECT_NE(ErrorOf({&mixed, &sim3, &dist3}, o).find("enumeration needs a purely binary space"),
            std::string::npos);

  const ParameterSpace small{BinarySpace::Independent(3)};
  o.thresholds = {1.0, 2.0};
  EXPECT_NE(ErrorOf({&small, &sim3, &dist3}, o).find("threshold and likelihood components"),
            std::string::npos);
  o.thresholds = {-1.0};
  EXPECT_NE(ErrorOf({&small, &sim3, &dist3}, o).find(">= 0"), std::string::npos);
}

class StopAfter : public SmcObserver {
 public:
  explicit StopAfter(int batches) : batches_(batches) {}
  void OnWaveStart(const WaveRecord& w) override { total = w.candidates; }
  void OnBatch(const BatchProgress& p, std::span<const Particle> accepted) override {
    ++seen;
    last = p.next_index;
    EXPECT_TRUE(accepted.empty());
  }
  void OnWaveEnd(const WaveRecord& w) override { ended = w.complete ? 1 : 2; }
  bool ShouldStop() override { return seen >= batches_; }
  std::int64_t total = 0, last = 0;
  int seen = 0, ended = 0;

 private:
  int batches_;
};

TEST(Enumeration, ObserverSeesProgressAndCanInterrupt) {
  Toy t;
  StopAfter all(1000);
  const auto full = Enumerate(t.problem(), Options(1), &all);
  EXPECT_EQ(all.total, 1024);
  EXPECT_EQ(all.seen, 11);  // batches of 100
  EXPECT_EQ(all.last, 1024);
  EXPECT_EQ(all.ended, 1);
  StopAfter two(2);
  const auto cut = Enumerate(t.problem(), Options(1), &two);
  EXPECT_TRUE(cut.interrupted);
  EXPECT_EQ(cut.enumerated, 200);
  EXPECT_EQ(two.ended, 2);
  EXPECT_LT(cut.accepted, full.accepted);
}

}  // namespace
}  // namespace combabc
