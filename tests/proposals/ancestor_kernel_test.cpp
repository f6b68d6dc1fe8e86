#include "combabc/proposals/ancestor_kernel.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "combabc/core/error.hpp"
#include "combabc/params/parameter_space.hpp"
#include "combabc/proposals/proposal_options.hpp"

namespace combabc {
namespace {

constexpr std::size_t kBits = 3;
constexpr std::size_t kReals = 2;
constexpr double kScale = 2.0;

// Three free bits and two reals with normal priors wide enough that truncation never matters.
ParameterSpace MixedSpace() {
  BinarySpaceOptions so;
  so.dimension = kBits;
  so.prior_one = {0.3, 0.5, 0.8};
  const ContinuousPrior wide{.kind = PriorKind::kNormal, .mean = 0.0, .sd = 10.0};
  return ParameterSpace(BinarySpace(so), {{"x", wide}, {"y", wide}});
}

// Three patterns: 20 particles around (0, 0), 14 around (3, -1) with correlated reals (their own
// covariances), and 3 around (1, 2) (too few: the population's covariance).
Population MakeMixedPopulation() {
  const std::array<std::array<std::uint8_t, kBits>, 3> patterns = {
      {{1, 0, 1}, {0, 1, 1}, {1, 1, 0}}};
  const std::array<std::array<double, 2>, 3> centres = {{{0.0, 0.0}, {3.0, -1.0}, {1.0, 2.0}}};
  const std::array<int, 3> counts = {20, 14, 3};
  Population p;
  p.num_free_bits = kBits;
  p.num_reals = kReals;
  RandomStream rng(7, 0, 0);
  double total = 0.0;
  for (std::size_t g = 0; g < 3; ++g) {
    for (int k = 0; k < counts[g]; ++k) {
      p.free_bits.insert(p.free_bits.end(), patterns[g].begin(), patterns[g].end());
      const double z = rng.Normal();
      p.reals.push_back(centres[g][0] + 0.3 * z);
      p.reals.push_back(centres[g][1] + 0.2 * rng.Normal() + (g == 1 ? 0.25 * z : 0.0));
      p.weights.push_back(0.8 + 0.4 * rng.Uniform());
      total += p.weights.back();
      ++p.size;
    }
  }
  for (double& w : p.weights) w /= total;
  return p;
}

Eigen::Vector2d RealsOf(const Population& p, std::size_t j) {
  return {p.reals[j * kReals], p.reals[j * kReals + 1]};
}

Eigen::Matrix2d Covariance(const Population& p, const std::vector<std::size_t>& js) {
  double total = 0.0;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto j : js) {
    total += p.weights[j];
    mean += p.weights[j] * RealsOf(p, j);
  }
  mean /= total;
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  for (const auto j : js) {
    const Eigen::Vector2d d = RealsOf(p, j) - mean;
    cov += p.weights[j] / total * d * d.transpose();
  }
  return cov;
}

double LogNormal(const Eigen::Vector2d& x, const Eigen::Vector2d& c, const Eigen::Matrix2d& s) {
  const Eigen::Vector2d d = x - c;
  return -std::log(2.0 * M_PI) - 0.5 * std::log(s.determinant()) - 0.5 * d.dot(s.inverse() * d);
}

// The mixture of ancestor_kernel.hpp written out term by term, with defensive weight a.
struct BruteForce {
  Population p;
  ParameterSpace space = MixedSpace();
  double a = 0.05;
  std::vector<double> flip;
  std::vector<Eigen::Matrix2d> sigma;  // per particle: its pattern's, or the population's

  explicit BruteForce(Population population) : p(std::move(population)) {
    for (std::size_t i = 0; i < kBits; ++i) {
      double m = 0.0;
      for (std::size_t j = 0; j < p.size; ++j) m += p.free_bits[j * kBits + i] * p.weights[j];
      flip.push_back(std::clamp(std::min(m, 1.0 - m), 0.1 / kBits, 0.5));
    }
    std::map<std::vector<std::uint8_t>, std::vector<std::size_t>> groups;
    std::vector<std::size_t> all;
    for (std::size_t j = 0; j < p.size; ++j) {
      groups[{p.free_bits.begin() + static_cast<long>(j * kBits),
              p.free_bits.begin() + static_cast<long>((j + 1) * kBits)}]
          .push_back(j);
      all.push_back(j);
    }
    const Eigen::Matrix2d global = kScale * Covariance(p, all);
    sigma.resize(p.size);
    for (const auto& [bits, js] : groups) {
      double w = 0.0, w2 = 0.0;
      for (const auto j : js) {
        w += p.weights[j];
        w2 += p.weights[j] * p.weights[j];
      }
      const Eigen::Matrix2d own = w * w / w2 >= 10.0 ? kScale * Covariance(p, js) : global;
      for (const auto j : js) sigma[j] = own;
    }
  }
  double Flips(std::size_t j, const std::vector<std::uint8_t>& b) const {
    double f = 1.0;
    for (std::size_t i = 0; i < kBits; ++i) {
      f *= b[i] == p.free_bits[j * kBits + i] ? 1.0 - flip[i] : flip[i];
    }
    return f;
  }
  double Density(const std::vector<std::uint8_t>& b, const Eigen::Vector2d& r) const {
    double q = 0.0;
    for (std::size_t j = 0; j < p.size; ++j) {
      q += p.weights[j] * Flips(j, b) * std::exp(LogNormal(r, RealsOf(p, j), sigma[j]));
    }
    const std::array<double, 2> reals = {r[0], r[1]};
    return (1.0 - a) * q + a * std::exp(space.LogPriorBits(b) + space.LogPriorReals(reals));
  }
  double BitsDensity(const std::vector<std::uint8_t>& b) const {
    double q = 0.0;
    for (std::size_t j = 0; j < p.size; ++j) q += p.weights[j] * Flips(j, b);
    return (1.0 - a) * q + a * std::exp(space.LogPriorBits(b));
  }
};

std::vector<std::uint8_t> Pattern(unsigned c) {
  std::vector<std::uint8_t> b(kBits);
  for (std::size_t i = 0; i < kBits; ++i) b[i] = static_cast<std::uint8_t>((c >> i) & 1U);
  return b;
}

std::unique_ptr<JointProposal> FitMixed(double phi = 0.0) {
  return MakeAncestorKernel(kScale)->Fit(MakeMixedPopulation(), MixedSpace(), {phi});
}

TEST(AncestorKernel, LogDensityMatchesTheMixtureWrittenOut) {
  const auto q = FitMixed();
  const BruteForce exact(MakeMixedPopulation());
  for (unsigned c = 0; c < (1U << kBits); ++c) {
    const auto b = Pattern(c);
    for (const Eigen::Vector2d& r : {Eigen::Vector2d(0.1, -0.2),
                                     Eigen::Vector2d(2.8, -0.7),
                                     Eigen::Vector2d(1.0, 2.0),
                                     Eigen::Vector2d(-6.0, 9.0)}) {
      const std::array<double, 2> reals = {r[0], r[1]};
      EXPECT_NEAR(q->LogDensity(b, reals), std::log(exact.Density(b, r)), 1e-8)
          << "pattern " << c << " at " << r.transpose();
    }
  }
}

TEST(AncestorKernel, TemperingRaisesTheDefensiveWeight) {
  const auto q = FitMixed(0.4);
  BruteForce exact(MakeMixedPopulation());
  exact.a = 0.4;
  const auto b = Pattern(5);
  const std::array<double, 2> reals = {0.2, 0.1};
  EXPECT_NEAR(q->LogDensity(b, reals), std::log(exact.Density(b, {0.2, 0.1})), 1e-8);
}

TEST(AncestorKernel, LogBitsDensityIsTheNormalisedMarginal) {
  const auto q = FitMixed();
  const BruteForce exact(MakeMixedPopulation());
  double sum = 0.0;
  for (unsigned c = 0; c < (1U << kBits); ++c) {
    const auto b = Pattern(c);
    EXPECT_NEAR(q->LogBitsDensity(b), std::log(exact.BitsDensity(b)), 1e-12);
    // The defensive mixture keeps every pattern: at least a p(b).
    EXPECT_GE(q->LogBitsDensity(b), std::log(0.05) + exact.space.LogPriorBits(b) - 1e-12);
    sum += std::exp(q->LogBitsDensity(b));
  }
  EXPECT_NEAR(sum, 1.0, 1e-12);
}

TEST(AncestorKernel, SampleFollowsLogBitsDensityAndMarginals) {
  const auto q = FitMixed();
  constexpr int kDraws = 100000;
  std::vector<int> count(1U << kBits, 0);
  std::vector<double> ones(kBits, 0.0);
  std::vector<std::uint8_t> b(kBits);
  std::vector<double> r(kReals);
  for (int k = 0; k < kDraws; ++k) {
    RandomStream rng(11, 1, static_cast<std::uint64_t>(k));
    q->Sample(rng, b, r);
    unsigned c = 0;
    for (std::size_t i = 0; i < kBits; ++i) {
      c |= static_cast<unsigned>(b[i]) << i;
      ones[i] += b[i];
    }
    ++count[c];
  }
  for (unsigned c = 0; c < (1U << kBits); ++c) {
    const double p = std::exp(q->LogBitsDensity(Pattern(c)));
    EXPECT_NEAR(count[c] / static_cast<double>(kDraws), p, 5.0 * std::sqrt(p * (1 - p) / kDraws))
        << "pattern " << c;
  }
  const auto m = q->Marginals();
  for (std::size_t i = 0; i < kBits; ++i) {
    EXPECT_NEAR(ones[i] / kDraws, m[i], 5.0 * std::sqrt(m[i] * (1 - m[i]) / kDraws)) << i;
  }
}

// The reals of a draw follow its ancestor: given the pattern (0, 1, 1), x has the mixture's
// conditional mean sum_j w_j F(b | b_j) x_j / sum_j w_j F(b | b_j) (the prior's part: mean 0).
TEST(AncestorKernel, RealsFollowTheAncestors) {
  const auto q = FitMixed();
  const BruteForce exact(MakeMixedPopulation());
  const std::vector<std::uint8_t> target = {0, 1, 1};
  double num = 0.0;
  for (std::size_t j = 0; j < exact.p.size; ++j) {
    num += (1.0 - exact.a) * exact.p.weights[j] * exact.Flips(j, target) * RealsOf(exact.p, j)[0];
  }
  const double expected = num / exact.BitsDensity(target);
  std::vector<std::uint8_t> b(kBits);
  std::vector<double> r(kReals);
  double sum = 0.0, sum2 = 0.0;
  int n = 0;
  for (int k = 0; k < 20000; ++k) {
    RandomStream rng(12, 1, static_cast<std::uint64_t>(k));
    q->Sample(rng, b, r);
    if (b == target) {
      sum += r[0];
      sum2 += r[0] * r[0];
      ++n;
    }
  }
  ASSERT_GT(n, 1000);
  const double mean = sum / n;
  const double sd = std::sqrt(sum2 / n - mean * mean);
  EXPECT_NEAR(mean, expected, 5.0 * sd / std::sqrt(n));
}

TEST(AncestorKernel, PriorAndEmptyPopulationAreThePrior) {
  const ParameterSpace space = MixedSpace();
  const auto kernel = MakeAncestorKernel(kScale);
  const std::array<double, 2> reals = {1.0, -2.0};
  const auto b = Pattern(6);
  const double prior = space.LogPriorBits(b) + space.LogPriorReals(reals);
  EXPECT_NEAR(kernel->Prior(space)->LogDensity(b, reals), prior, 1e-12);
  Population empty;
  empty.num_free_bits = kBits;
  empty.num_reals = kReals;
  EXPECT_NEAR(kernel->Fit(empty, space, {})->LogDensity(b, reals), prior, 1e-12);
  EXPECT_EQ(kernel->Prior(space)->Marginals(), space.binary().free_prior_one());
}

TEST(AncestorKernel, OptionsChooseItAndRefuseAnotherContinuousKernel) {
  const ParameterSpace space = MixedSpace();
  ProposalOptions o;
  o.binary = BinaryKernelKind::kAncestor;
  EXPECT_EQ(MakeJointKernel(o, space)->name(), "ancestor");
  EXPECT_THROW(MakeBinaryKernel(o), Error);
  o.continuous = ContinuousKernelKind::kOlcm;
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why,
            "ProposalOptions::continuous = olcm; the ancestor kernel proposes the reals itself "
            "(continuous = normal)");
  EXPECT_THROW(MakeJointKernel(o, space), Error);
  EXPECT_THROW(MakeAncestorKernel(0.0), Error);
}

// The default (kAuto) is the ancestor kernel for a mixed space with the normal kernel, the
// independent product kernel for bits alone, reals alone, or another continuous kernel.
TEST(AncestorKernel, TheDefaultIsTheAncestorKernelForMixedSpacesOnly) {
  const ProposalOptions o;
  EXPECT_EQ(o.binary, BinaryKernelKind::kAuto);
  EXPECT_EQ(ResolvedProposal(o, true).binary, BinaryKernelKind::kAncestor);
  EXPECT_EQ(ResolvedProposal(o, false).binary, BinaryKernelKind::kIndependent);
  ProposalOptions olcm;
  olcm.continuous = ContinuousKernelKind::kOlcm;
  EXPECT_EQ(ResolvedProposal(olcm, true).binary, BinaryKernelKind::kIndependent);
  ProposalOptions logistic;
  logistic.binary = BinaryKernelKind::kLogistic;
  EXPECT_EQ(ResolvedProposal(logistic, true).binary, BinaryKernelKind::kLogistic);
  EXPECT_EQ(MakeJointKernel(o, MixedSpace())->name(), "ancestor");
  EXPECT_THROW(MakeBinaryKernel(o), Error);  // not resolved
}

// A fixed or dummy bit (prior 0 or 1) is never flipped (issue 35: about 10 % of a wave's accepted
// particles carried weight 0, their fixed bit flipped to a value of prior 0), the floor of the
// flip rates spreads over the other bits, and the density stays exact: the proposal gives the
// impossible values probability 0 and still sums to 1.
TEST(AncestorKernel, BitsWhosePriorIsZeroOrOneAreNeverFlipped) {
  BinarySpaceOptions so;
  so.dimension = 4;
  so.prior_one = {0.0, 0.5, 1.0, 0.5};
  const ContinuousPrior wide{.kind = PriorKind::kNormal, .mean = 0.0, .sd = 10.0};
  const ParameterSpace space(BinarySpace(so), {{"x", wide}});
  Population p;
  p.num_free_bits = 4;
  p.num_reals = 1;
  for (int k = 0; k < 20; ++k) {
    const std::array<std::uint8_t, 4> bits = {0, static_cast<std::uint8_t>(k % 2), 1, 1};
    p.free_bits.insert(p.free_bits.end(), bits.begin(), bits.end());
    p.reals.push_back(0.1 * k);
    p.weights.push_back(1.0 / 20);
    ++p.size;
  }
  const auto q = MakeAncestorKernel(kScale)->Fit(p, space, {});
  std::vector<std::uint8_t> b(4);
  std::vector<double> r(1);
  int moved = 0;  // draws that flipped bit 3, which the population holds at 1 (floor 0.1 / 2)
  for (int k = 0; k < 20000; ++k) {
    RandomStream rng(13, 1, static_cast<std::uint64_t>(k));
    q->Sample(rng, b, r);
    ASSERT_EQ(b[0], 0) << "draw " << k;
    ASSERT_EQ(b[2], 1) << "draw " << k;
    moved += b[3] == 0 ? 1 : 0;
  }
  // (1 - a) 0.05 + a 0.5 = 0.0725 with a = 0.05 (the floor 0.1 / 4 would give 0.049).
  EXPECT_NEAR(moved / 20000.0, 0.0725, 5.0 * std::sqrt(0.0725 * 0.9275 / 20000));
  double sum = 0.0;
  for (unsigned c = 0; c < 16; ++c) {
    std::vector<std::uint8_t> pattern(4);
    for (std::size_t i = 0; i < 4; ++i) pattern[i] = static_cast<std::uint8_t>((c >> i) & 1U);
    const double log_q = q->LogBitsDensity(pattern);
    if (pattern[0] == 1 || pattern[2] == 0) {
      EXPECT_EQ(log_q, -std::numeric_limits<double>::infinity()) << c;
      const std::array<double, 1> x = {0.5};
      EXPECT_EQ(q->LogDensity(pattern, x), -std::numeric_limits<double>::infinity()) << c;
    }
    sum += std::exp(log_q);
  }
  EXPECT_NEAR(sum, 1.0, 1e-12);
  const auto m = q->Marginals();
  EXPECT_EQ(m[0], 0.0);
  EXPECT_DOUBLE_EQ(m[2], 1.0);
}

// `auto` looks at the bits the data can inform: a space whose bits all have prior 0 or 1 and a
// real is continuous to it (issue 35: a fixed or dummy bit switched it to the ancestor kernel).
TEST(AncestorKernel, TheDefaultIgnoresFixedBits) {
  BinarySpaceOptions so;
  so.dimension = 2;
  so.prior_one = {0.0, 1.0};
  const ContinuousPrior wide{.kind = PriorKind::kNormal, .mean = 0.0, .sd = 10.0};
  const ParameterSpace fixed(BinarySpace(so), {{"x", wide}});
  EXPECT_EQ(MakeJointKernel(ProposalOptions{}, fixed)->name(), "independent");
  so.prior_one = {0.0, 0.4};
  const ParameterSpace one_free(BinarySpace(so), {{"x", wide}});
  EXPECT_EQ(MakeJointKernel(ProposalOptions{}, one_free)->name(), "ancestor");
  EXPECT_FALSE(AnyUncertainBit(std::vector<double>{0.0, 1.0}));
  EXPECT_TRUE(AnyUncertainBit(std::vector<double>{1.0, 0.999}));
  EXPECT_FALSE(AnyUncertainBit(std::vector<double>{}));
}

}  // namespace
}  // namespace combabc
