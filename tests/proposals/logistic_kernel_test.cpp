#include "combabc/proposals/logistic_kernel.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "combabc/core/error.hpp"
#include "combabc/rng/random_stream.hpp"
#include "proposals/weighted_logistic_regression.hpp"

namespace combabc {
namespace {

// Sums of 2^10 probabilities, each exact to a few ulps.
constexpr double kNormalisationTol = 1e-12;

using Bits = std::vector<std::uint8_t>;

// Configuration number c as bits: x_i = bit i of c.
Bits ConfigurationOf(std::uint32_t c, std::size_t f) {
  Bits x(f);
  for (std::size_t i = 0; i < f; ++i) x[i] = static_cast<std::uint8_t>((c >> i) & 1U);
  return x;
}

Population MakePopulation(const std::vector<Bits>& rows, const std::vector<double>& weights) {
  Population p;
  p.size = rows.size();
  p.num_free_bits = rows.empty() ? 0 : rows[0].size();
  for (const auto& r : rows) p.free_bits.insert(p.free_bits.end(), r.begin(), r.end());
  p.weights = weights;
  p.within_next.assign(rows.size(), 1);
  return p;
}

Population EqualWeights(const std::vector<Bits>& rows) {
  return MakePopulation(rows,
                        std::vector<double>(rows.size(), 1.0 / static_cast<double>(rows.size())));
}

// A population with couplings at lags 1 and 2 and unequal weights, for the exactness checks.
Population CoupledPopulation(std::size_t f, std::size_t n, std::uint64_t seed) {
  RandomStream rng(seed, 0, 0);
  std::vector<Bits> rows;
  std::vector<double> weights;
  double total = 0.0;
  for (std::size_t r = 0; r < n; ++r) {
    Bits x(f);
    for (std::size_t i = 0; i < f; ++i) {
      double p = 0.3;
      if (i >= 1) p = x[i - 1] ? 0.8 : 0.25;
      if (i >= 2 && x[i - 2]) p = 0.5 * p + 0.1;
      x[i] = static_cast<std::uint8_t>(rng.Uniform() < p);
    }
    rows.push_back(x);
    weights.push_back(0.2 + rng.Uniform());
    total += weights.back();
  }
  for (auto& w : weights) w /= total;
  return MakePopulation(rows, weights);
}

// x_0 ~ Bernoulli(1/2), x_{i+1} = x_i with probability 0.9, else flipped.
std::vector<Bits> ChainRows(std::size_t f, std::size_t n, std::uint64_t seed) {
  RandomStream rng(seed, 0, 0);
  std::vector<Bits> rows;
  for (std::size_t r = 0; r < n; ++r) {
    Bits x(f);
    x[0] = static_cast<std::uint8_t>(rng.Uniform() < 0.5);
    for (std::size_t i = 1; i < f; ++i) {
      x[i] = static_cast<std::uint8_t>(rng.Uniform() < 0.9 ? x[i - 1] : 1 - x[i - 1]);
    }
    rows.push_back(x);
  }
  return rows;
}

std::vector<double> SkewedPrior(std::size_t f) {
  std::vector<double> prior(f);
  for (std::size_t i = 0; i < f; ++i) {
    prior[i] = 0.2 + 0.6 * static_cast<double>(i) / static_cast<double>(f);
  }
  return prior;
}

// P(x_i = 1 | x_<i = prefix) under q, by summing exp(LogDensity) over every suffix.
double ConditionalOne(const BinaryProposal& q, const Bits& prefix, std::size_t f) {
  const std::size_t i = prefix.size();
  double one = 0.0, any = 0.0;
  for (std::uint32_t s = 0; s < (1U << (f - i)); ++s) {
    Bits x = prefix;
    const Bits suffix = ConfigurationOf(s, f - i);
    x.insert(x.end(), suffix.begin(), suffix.end());
    const double mass = std::exp(q.LogDensity(x));
    any += mass;
    if (x[i]) one += mass;
  }
  return one / any;
}

struct TemperingCase {
  const char* name;
  Tempering tempering;
};
const std::vector<TemperingCase> kTemperings = {
    {"phi 0", {0.0, TemperingForm::kGeometric}},
    {"phi 0.3 geometric", {0.3, TemperingForm::kGeometric}},
    {"phi 0.3 mixture", {0.3, TemperingForm::kMixture}},
    {"phi 1 geometric", {1.0, TemperingForm::kGeometric}},
    {"phi 1 mixture", {1.0, TemperingForm::kMixture}},
};

TEST(LogisticKernel, DensitySumsToOneOverAllConfigurations) {
  constexpr std::size_t f = 10;
  const auto kernel = MakeLogisticKernel({});
  const auto population = CoupledPopulation(f, 400, 11);
  for (const auto& c : kTemperings) {
    const auto q = kernel->Fit(population, SkewedPrior(f), c.tempering);
    double total = 0.0;
    for (std::uint32_t x = 0; x < (1U << f); ++x) {
      total += std::exp(q->LogDensity(ConfigurationOf(x, f)));
    }
    EXPECT_NEAR(total, 1.0, kNormalisationTol) << c.name;
  }
}

TEST(LogisticKernel, PhiOneEmptyPopulationAndZeroWeightGiveThePrior) {
  constexpr std::size_t f = 6;
  const auto prior = SkewedPrior(f);
  const auto kernel = MakeLogisticKernel({});
  auto zero_weight = CoupledPopulation(f, 50, 3);
  zero_weight.weights.assign(zero_weight.size, 0.0);
  Population empty;
  empty.num_free_bits = f;
  std::vector<std::unique_ptr<BinaryProposal>> proposals;
  proposals.push_back(
      kernel->Fit(CoupledPopulation(f, 200, 2), prior, {1.0, TemperingForm::kGeometric}));
  proposals.push_back(
      kernel->Fit(CoupledPopulation(f, 200, 2), prior, {1.0, TemperingForm::kMixture}));
  proposals.push_back(kernel->Fit(empty, prior, {0.0, TemperingForm::kGeometric}));
  proposals.push_back(kernel->Fit(zero_weight, prior, {0.0, TemperingForm::kGeometric}));
  for (std::size_t k = 0; k < proposals.size(); ++k) {
    for (std::uint32_t c = 0; c < (1U << f); ++c) {
      const Bits x = ConfigurationOf(c, f);
      double log_prior = 0.0;
      for (std::size_t i = 0; i < f; ++i) log_prior += std::log(x[i] ? prior[i] : 1.0 - prior[i]);
      EXPECT_DOUBLE_EQ(proposals[k]->LogDensity(x), log_prior) << "proposal " << k << " at " << c;
    }
    EXPECT_EQ(proposals[k]->Marginals(), prior) << "proposal " << k;
  }
}

TEST(LogisticKernel, APriorOfZeroOrOneFixesItsBitOnceTempered) {
  // Eq. 3 with prior P(1) = 0 or 1 gives that value with certainty for any phi > 0; the mixture
  // keeps the fit's share. Either way q must stay normalised and Sample must stay in q's support.
  constexpr std::size_t f = 5;
  auto prior = SkewedPrior(f);
  prior[1] = 0.0;
  prior[3] = 1.0;
  const auto population = CoupledPopulation(f, 300, 8);
  for (const auto form : {TemperingForm::kGeometric, TemperingForm::kMixture}) {
    const auto q = MakeLogisticKernel({})->Fit(population, prior, {0.3, form});
    double total = 0.0;
    for (std::uint32_t c = 0; c < (1U << f); ++c) {
      const Bits x = ConfigurationOf(c, f);
      const double density = q->LogDensity(x);
      EXPECT_FALSE(std::isnan(density));
      total += std::exp(density);
      if (form == TemperingForm::kGeometric && (x[1] == 1 || x[3] == 0)) {
        EXPECT_EQ(density, -std::numeric_limits<double>::infinity()) << c;
      }
    }
    EXPECT_NEAR(total, 1.0, kNormalisationTol);
    RandomStream rng(3, 3, 3);
    Bits x(f);
    for (int k = 0; k < 1000; ++k) {
      q->Sample(rng, x);
      ASSERT_TRUE(std::isfinite(q->LogDensity(x)));
    }
  }
}

TEST(LogisticKernel, SampleFrequenciesMatchTheDensity) {
  // 200k draws per tempering; each configuration's count is Binomial(n, q(x)), checked to within
  // 6 standard deviations plus one count of discreteness (a false alarm has probability < 1e-7
  // over the 64 x 3 cells). Sampling from the wrong conditionals, or a density that does not match
  // the sampler (e.g. a mixture whose selector draw is mis-ordered), moves cells by far more.
  constexpr std::size_t f = 6;
  constexpr int n = 200000;
  const auto kernel = MakeLogisticKernel({});
  const auto population = CoupledPopulation(f, 300, 5);
  for (std::size_t t = 0; t < 3; ++t) {
    const auto q = kernel->Fit(population, SkewedPrior(f), kTemperings[t].tempering);
    std::vector<int> count(1U << f, 0);
    RandomStream rng(77, 1, t);
    Bits x(f);
    for (int k = 0; k < n; ++k) {
      q->Sample(rng, x);
      std::uint32_t c = 0;
      for (std::size_t i = 0; i < f; ++i) c |= static_cast<std::uint32_t>(x[i]) << i;
      ++count[c];
    }
    for (std::uint32_t c = 0; c < (1U << f); ++c) {
      const double p = std::exp(q->LogDensity(ConfigurationOf(c, f)));
      const double sigma = std::sqrt(n * p * (1.0 - p));
      EXPECT_LE(std::abs(count[c] - n * p), 6.0 * sigma + 1.0)
          << kTemperings[t].name << " at " << c;
    }
  }
}

TEST(LogisticKernel, BitsWithMoreThanTenPredecessorsAreExactToo) {
  // Bits with at most 10 predecessors are tabulated per pattern; the last four bits here have 11
  // to 14 and take the per-candidate path. Their conditionals must depend on their far predecessors
  // (else the fit fell back to the marginal and this path went untested), the density must sum
  // to one, and Sample must draw x_14 as often as the density says.
  constexpr std::size_t f = 15;
  LogisticKernelOptions options;
  options.min_correlation = 0.0;
  options.max_predecessors = 14;
  const auto kernel = MakeLogisticKernel(options);
  const auto population = CoupledPopulation(f, 2000, 3);
  for (std::size_t t = 0; t < 3; ++t) {
    const auto q = kernel->Fit(population, SkewedPrior(f), kTemperings[t].tempering);
    Bits prefix(f - 1, 0);
    const double without_x0 = ConditionalOne(*q, prefix, f);
    prefix[0] = 1;
    EXPECT_GT(std::abs(ConditionalOne(*q, prefix, f) - without_x0), 1e-6) << kTemperings[t].name;
    double total = 0.0, last_one = 0.0;
    for (std::uint32_t c = 0; c < (1U << f); ++c) {
      const Bits x = ConfigurationOf(c, f);
      const double mass = std::exp(q->LogDensity(x));
      total += mass;
      if (x[f - 1]) last_one += mass;
    }
    EXPECT_NEAR(total, 1.0, 1e-11) << kTemperings[t].name;
    constexpr int n = 100000;
    RandomStream rng(78, 1, t);
    Bits x(f);
    int ones = 0;
    for (int k = 0; k < n; ++k) {
      q->Sample(rng, x);
      ones += x[f - 1];
    }
    EXPECT_LE(std::abs(ones - n * last_one), 6.0 * std::sqrt(n * last_one * (1.0 - last_one)) + 1.0)
        << kTemperings[t].name;
  }
}

TEST(LogisticKernel, ConcentratesOnAConfigurationAndItsComplement) {
  // 480 of 500 rows are c or its complement, 20 are uniform noise. The independent kernel sees
  // marginals near 1/2 and puts about 2 x 2^-16 on {c, ~c}; the conditionals see that each bit
  // copies (or negates) the ones before it.
  constexpr std::size_t f = 16;
  RandomStream rng(2024, 0, 0);
  Bits c(f), complement(f);
  for (std::size_t i = 0; i < f; ++i) {
    c[i] = static_cast<std::uint8_t>(rng.Uniform() < 0.5);
    complement[i] = static_cast<std::uint8_t>(1 - c[i]);
  }
  std::vector<Bits> rows;
  for (int r = 0; r < 240; ++r) {
    rows.push_back(c);
    rows.push_back(complement);
  }
  for (int r = 0; r < 20; ++r) {
    Bits noise(f);
    for (auto& b : noise) b = static_cast<std::uint8_t>(rng.Uniform() < 0.5);
    rows.push_back(noise);
  }
  const auto q = MakeLogisticKernel({})->Fit(EqualWeights(rows), std::vector<double>(f, 0.5), {});
  const double mass_c = std::exp(q->LogDensity(c));
  const double mass_complement = std::exp(q->LogDensity(complement));
  EXPECT_GT(mass_c + mass_complement, 0.8);
  EXPECT_GT(mass_c, 0.3);
  EXPECT_GT(mass_complement, 0.3);
}

TEST(LogisticKernel, RecoversAChainCoupling) {
  // True conditionals: P(x_i = 1 | x_<i) = 0.9 if x_{i-1} = 1 else 0.1, whatever came before.
  // 20000 rows estimate them to about +-0.01 (+-0.02 after a rare mixed prefix, where the small
  // slopes fitted to x_{i-2}, ... add up); the bound 0.03 catches a kernel that ignores the
  // coupling (0.5). The default ridge (1e-3) shrinks the slope of x_{i-1} onto its correlated
  // neighbours, which costs ~0.05 after a mixed prefix, so that check uses a negligible ridge.
  constexpr std::size_t f = 8;
  const auto population = EqualWeights(ChainRows(f, 20000, 9));
  LogisticKernelOptions unbiased;
  unbiased.ridge = 1e-6;
  const auto q = MakeLogisticKernel(unbiased)->Fit(population, std::vector<double>(f, 0.5), {});
  const auto q_default = MakeLogisticKernel({})->Fit(population, std::vector<double>(f, 0.5), {});
  EXPECT_NEAR(ConditionalOne(*q, {}, f), 0.5, 0.03);
  for (std::size_t i = 1; i < f; ++i) {
    const Bits ones(i, 1), zeros(i, 0);
    Bits alternating(i), last_flipped(i, 0);
    for (std::size_t k = 0; k < i; ++k) alternating[k] = static_cast<std::uint8_t>((i - k) % 2);
    last_flipped[i - 1] = 1;
    EXPECT_NEAR(ConditionalOne(*q, ones, f), 0.9, 0.03) << "bit " << i;
    EXPECT_NEAR(ConditionalOne(*q, zeros, f), 0.1, 0.03) << "bit " << i;
    EXPECT_NEAR(ConditionalOne(*q, alternating, f), 0.9, 0.03) << "bit " << i;  // ends in 1
    EXPECT_NEAR(ConditionalOne(*q, last_flipped, f), 0.9, 0.03) << "bit " << i;
    EXPECT_NEAR(ConditionalOne(*q_default, ones, f), 0.9, 0.03) << "bit " << i;
    EXPECT_NEAR(ConditionalOne(*q_default, zeros, f), 0.1, 0.03) << "bit " << i;
  }
  // The marginals of the chain are 1/2; the Monte-Carlo estimate of the fit's marginals is within
  // its own error (~0.01) plus the fit's.
  for (const double m : q->Marginals()) EXPECT_NEAR(m, 0.5, 0.05);
}

TEST(LogisticKernel, NearConstantBitsUseTheirMarginalAndAreNoPredecessor) {
  // Bit 2 is 1 in 99.5 % of rows (below min_marginal = 0.02 from 1), and 0 only where bit 0 is 0;
  // bit 3 is always 0; bit 5 = bit 2 AND a coin. With min_correlation lowered to 0.01, bit 2 would
  // be one of bit 5's predecessors (|corr| ~ 0.07) if near-constant bits were not skipped.
  constexpr std::size_t f = 6;
  RandomStream rng(31, 0, 0);
  std::vector<Bits> rows;
  for (int r = 0; r < 1000; ++r) {
    Bits x(f);
    x[0] = static_cast<std::uint8_t>(r < 5 ? 0 : rng.Uniform() < 0.5);
    x[1] = static_cast<std::uint8_t>(rng.Uniform() < 0.5);
    x[2] = static_cast<std::uint8_t>(r >= 5);
    x[3] = 0;
    x[4] = static_cast<std::uint8_t>(rng.Uniform() < 0.5);
    x[5] = static_cast<std::uint8_t>(x[2] && rng.Uniform() < 0.5);
    rows.push_back(x);
  }
  LogisticKernelOptions options;
  options.min_correlation = 0.01;
  const auto q =
      MakeLogisticKernel(options)->Fit(EqualWeights(rows), std::vector<double>(f, 0.5), {});
  for (std::uint32_t prefix = 0; prefix < 4; ++prefix) {
    EXPECT_NEAR(ConditionalOne(*q, ConfigurationOf(prefix, 2), f), 0.995, 1e-12) << prefix;
    Bits x = ConfigurationOf(prefix, 2);
    x.push_back(1);
    EXPECT_NEAR(ConditionalOne(*q, x, f), options.clip, 1e-12) << prefix;  // bit 3, clipped
  }
  for (std::uint32_t other = 0; other < 16; ++other) {  // x_0, x_1, x_3, x_4
    Bits with2 = {static_cast<std::uint8_t>(other & 1U),
                  static_cast<std::uint8_t>((other >> 1) & 1U),
                  1,
                  static_cast<std::uint8_t>((other >> 2) & 1U),
                  static_cast<std::uint8_t>((other >> 3) & 1U)};
    Bits without2 = with2;
    without2[2] = 0;
    EXPECT_NEAR(ConditionalOne(*q, with2, f), ConditionalOne(*q, without2, f), 1e-12) << other;
  }
}

TEST(LogisticKernel, FitsTheWeightedPopulation) {
  // The same six rows (00 and 11 twice) under two weightings. Two bits with all four
  // configurations present make the regression of x_1 on x_0 saturated, so with a negligible
  // ridge the fit reproduces the weighted joint exactly; duplicates must have their weights summed.
  const std::vector<Bits> rows = {{0, 0}, {0, 0}, {0, 1}, {1, 0}, {1, 1}, {1, 1}};
  LogisticKernelOptions options;
  options.ridge = 1e-12;
  const auto kernel = MakeLogisticKernel(options);
  struct Case {
    std::vector<double> weights;
    std::vector<double> joint;  // q(00), q(10), q(01), q(11) (configuration number order)
  };
  const std::vector<Case> cases = {
      {{0.25, 0.15, 0.1, 0.1, 0.3, 0.1}, {0.4, 0.1, 0.1, 0.4}},
      {{0.125, 0.125, 0.25, 0.25, 0.2, 0.05}, {0.25, 0.25, 0.25, 0.25}},
      {std::vector<double>(6, 1.0 / 6.0), {2.0 / 6.0, 1.0 / 6.0, 1.0 / 6.0, 2.0 / 6.0}},
  };
  for (std::size_t k = 0; k < cases.size(); ++k) {
    const auto q = kernel->Fit(MakePopulation(rows, cases[k].weights), {0.5, 0.5}, {});
    for (std::uint32_t c = 0; c < 4; ++c) {
      EXPECT_NEAR(std::exp(q->LogDensity(ConfigurationOf(c, 2))), cases[k].joint[c], 1e-6)
          << "case " << k << " configuration " << c;
    }
  }
}

TEST(LogisticKernel, GeometricTemperingOfIndependentBitsIsEquation3) {
  // Every configuration with product weights: the bits are exactly independent, no predecessor
  // passes the correlation test, and the tempered kernel must be Eq. 3 per bit (the mixture form
  // the joint mixture of the two products).
  constexpr std::size_t f = 4;
  const std::vector<double> m = {0.3, 0.6, 0.5, 0.85};
  const auto prior = SkewedPrior(f);
  std::vector<Bits> rows;
  std::vector<double> weights;
  for (std::uint32_t c = 0; c < (1U << f); ++c) {
    rows.push_back(ConfigurationOf(c, f));
    double w = 1.0;
    for (std::size_t i = 0; i < f; ++i) w *= rows.back()[i] ? m[i] : 1.0 - m[i];
    weights.push_back(w);
  }
  const auto kernel = MakeLogisticKernel({});
  const double phi = 0.3;
  const auto geometric =
      kernel->Fit(MakePopulation(rows, weights), prior, {phi, TemperingForm::kGeometric});
  const auto mixture =
      kernel->Fit(MakePopulation(rows, weights), prior, {phi, TemperingForm::kMixture});
  for (std::uint32_t c = 0; c < (1U << f); ++c) {
    const Bits x = ConfigurationOf(c, f);
    double eq3 = 1.0, fit = 1.0, p = 1.0;
    for (std::size_t i = 0; i < f; ++i) {
      const double t = TemperedProbability(m[i], prior[i], phi, TemperingForm::kGeometric);
      eq3 *= x[i] ? t : 1.0 - t;
      fit *= x[i] ? m[i] : 1.0 - m[i];
      p *= x[i] ? prior[i] : 1.0 - prior[i];
    }
    EXPECT_NEAR(std::exp(geometric->LogDensity(x)), eq3, 1e-9 * eq3) << c;
    EXPECT_NEAR(std::exp(mixture->LogDensity(x)), (1 - phi) * fit + phi * p, 1e-9) << c;
  }
  const auto marginals = geometric->Marginals();
  for (std::size_t i = 0; i < f; ++i) {
    EXPECT_NEAR(
        marginals[i], TemperedProbability(m[i], prior[i], phi, TemperingForm::kGeometric), 1e-9);
  }
}

TEST(LogisticKernel, SameInputsSameProposalBitForBit) {
  constexpr std::size_t f = 10;
  const auto population = CoupledPopulation(f, 500, 17);
  for (const auto& c : kTemperings) {
    const auto a = MakeLogisticKernel({})->Fit(population, SkewedPrior(f), c.tempering);
    const auto b = MakeLogisticKernel({})->Fit(population, SkewedPrior(f), c.tempering);
    for (std::uint32_t x = 0; x < (1U << f); ++x) {
      const Bits bits = ConfigurationOf(x, f);
      ASSERT_EQ(a->LogDensity(bits), b->LogDensity(bits)) << c.name;
    }
    EXPECT_EQ(a->Marginals(), b->Marginals()) << c.name;
    RandomStream ra(5, 6, 7), rb(5, 6, 7);
    Bits xa(f), xb(f);
    for (int k = 0; k < 100; ++k) {
      a->Sample(ra, xa);
      b->Sample(rb, xb);
      ASSERT_EQ(xa, xb) << c.name;
    }
  }
}

TEST(LogisticKernel, InvalidOptionsThrowWithTheFieldName) {
  LogisticKernelOptions options;
  options.clip = 0.0;
  try {
    MakeLogisticKernel(options);
    FAIL() << "no exception";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("LogisticKernelOptions::clip"), std::string::npos)
        << e.what();
  }
}

TEST(WeightedLogisticRegression, ConvergesOnSeparableDataAndGivesUpWhenOutOfIterations) {
  // y = x exactly: unpenalised, the slope would diverge. With the ridge the optimum is finite
  // (slope ~ 8.1 for ridge 1e-3: 0.5 (1 - sigmoid(b / 2)) = ridge b), and there the penalised
  // score must vanish.
  Eigen::MatrixXd design(2, 2);
  design << 1, 0, 1, 1;
  const Eigen::VectorXd y = (Eigen::VectorXd(2) << 0, 1).finished();
  const Eigen::VectorXd w = (Eigen::VectorXd(2) << 0.5, 0.5).finished();
  WeightedLogisticOptions options;
  options.ridge = 1e-3;
  const auto beta = FitWeightedLogistic(design, y, w, Eigen::VectorXd::Zero(2), options);
  ASSERT_TRUE(beta.has_value());
  EXPECT_GT((*beta)[1], 7.0);
  EXPECT_LT((*beta)[1], 9.0);
  const Eigen::ArrayXd p = 1.0 / (1.0 + (-(design * *beta).array()).exp());
  Eigen::VectorXd score = design.transpose() * (w.array() * (y.array() - p)).matrix();
  score[1] -= options.ridge * (*beta)[1];
  EXPECT_LT(score.lpNorm<Eigen::Infinity>(), 1e-10);
  options.max_iterations = 2;
  EXPECT_FALSE(FitWeightedLogistic(design, y, w, Eigen::VectorXd::Zero(2), options).has_value());
}

TEST(WeightedLogisticRegression, MergedRowsGiveTheSameFitAsTheRows) {
  // Rows with equal design rows merged into one, with summed weight and y their weighted fraction
  // of ones, have the same likelihood: the kernel fits on merged rows.
  Eigen::MatrixXd design(6, 2);
  design << 1, 0, 1, 0, 1, 0, 1, 1, 1, 1, 1, 1;
  const Eigen::VectorXd y = (Eigen::VectorXd(6) << 1, 0, 0, 1, 1, 0).finished();
  const Eigen::VectorXd w = (Eigen::VectorXd(6) << 0.1, 0.2, 0.1, 0.3, 0.2, 0.1).finished();
  Eigen::MatrixXd merged_design(2, 2);
  merged_design << 1, 0, 1, 1;
  const Eigen::VectorXd merged_w = (Eigen::VectorXd(2) << 0.4, 0.6).finished();
  const Eigen::VectorXd merged_y = (Eigen::VectorXd(2) << 0.1 / 0.4, 0.5 / 0.6).finished();
  const WeightedLogisticOptions options;
  const auto rows = FitWeightedLogistic(design, y, w, Eigen::VectorXd::Zero(2), options);
  const auto merged =
      FitWeightedLogistic(merged_design, merged_y, merged_w, Eigen::VectorXd::Zero(2), options);
  ASSERT_TRUE(rows.has_value());
  ASSERT_TRUE(merged.has_value());
  // Ones in 1/4 of the x = 0 weight and 5/6 of the x = 1 weight: a clear positive slope
  // (unpenalised it would be logit(5/6) - logit(1/4) = 2.7).
  EXPECT_GT((*rows)[1], 2.0);
  EXPECT_NEAR((*merged)[0], (*rows)[0], 1e-9);
  EXPECT_NEAR((*merged)[1], (*rows)[1], 1e-9);
}

}  // namespace
}  // namespace combabc
