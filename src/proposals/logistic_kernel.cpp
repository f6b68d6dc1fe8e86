#include "combabc/proposals/logistic_kernel.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <utility>

#include "combabc/core/check.hpp"
#include "combabc/core/error.hpp"
#include "proposals/log_sum_exp.hpp"
#include "proposals/weighted_logistic_regression.hpp"

namespace combabc {
namespace {

// Marginals() has no closed form once bits are coupled: it averages P(x_j = 1 | x_<j) over this
// many forward draws, draw k from RandomStream(kMarginalsSeed, 0, k), so the estimate is the same
// on every run (it is only recorded for reports; Rao-Blackwellised, its error is well below
// 1 / sqrt(1024) ~ 0.03).
constexpr std::uint64_t kMarginalsSeed = 0x1061571c;
constexpr int kMarginalsDraws = 1024;

// log(p / (1 - p)); -inf at 0 and +inf at 1.
double Logit(double p) { return std::log(p) - std::log1p(-p); }

// Independent Bernoulli bits: the prior (wave 0, an empty population, phi = 1).
class IndependentBernoulliProposal final : public BinaryProposal {
 public:
  explicit IndependentBernoulliProposal(std::vector<double> prob_one)
      : prob_one_(std::move(prob_one)) {
    for (const double p : prob_one_) {
      COMBABC_CHECK(p >= 0.0 && p <= 1.0);
      log_one_.push_back(std::log(p));
      log_zero_.push_back(std::log1p(-p));
    }
  }

  void Sample(RandomStream& rng, std::span<std::uint8_t> free_bits) const override {
    for (std::size_t i = 0; i < prob_one_.size(); ++i) {
      free_bits[i] = static_cast<std::uint8_t>(rng.Uniform() < prob_one_[i]);
    }
  }

  double LogDensity(std::span<const std::uint8_t> free_bits) const override {
    double sum = 0.0;
    for (std::size_t i = 0; i < prob_one_.size(); ++i) {
      sum += free_bits[i] ? log_one_[i] : log_zero_[i];
    }
    return sum;
  }

  std::vector<double> Marginals() const override { return prob_one_; }

 private:
  std::vector<double> prob_one_;
  std::vector<double> log_one_;
  std::vector<double> log_zero_;
};

// Conditionals with at most this many predecessors are tabulated: one entry per pattern of their
// predecessors (2^s of them, 24 bytes each: 6 KiB per bit at the default max_predecessors = 8).
// Sample, LogDensity and Marginals then cost a table lookup per bit instead of an exp (and a log),
// and the fit regresses on the at most 2^s patterns instead of the population's rows. Bits with
// more predecessors (only with max_predecessors > 10) evaluate their logit per candidate: their
// tables (24 KiB per bit at s = 10, 100 MB for 1024 bits at s = 12) would cost more to build
// and hold than a wave's candidates save.
constexpr std::size_t kMaxTabulatedPredecessors = 10;

// One conditional q(x_i | x_<i) with logit L: P(x_i = 1) and log q for x_i = 0 and 1. Sample and
// LogDensity read the same entry, so the density is exact for what Sample draws; L = -inf or +inf
// (a tempered prior of 0 or 1) gives probability 0 or 1 and log q = -inf for the other value.
struct ConditionalEntry {
  double prob_one = 0.0;
  std::array<double, 2> log_q{};  // log q(x_i = 0 | .), log q(x_i = 1 | .)
};

// One exp and one log1p: with e = exp(-|L|), sigmoid(L) is 1 / (1 + e) or e / (1 + e) and
// softplus(+-L) = max(+-L, 0) + log1p(e).
ConditionalEntry EntryOfLogit(double logit) {
  const double e = std::exp(-std::abs(logit));
  const double log1p_e = std::log1p(e);
  return {logit >= 0.0 ? 1.0 / (1.0 + e) : e / (1.0 + e),
          {-(std::max(logit, 0.0) + log1p_e), -(std::max(-logit, 0.0) + log1p_e)}};
}

// The fitted conditionals in flat arrays, so that a candidate's Sample and LogDensity touch a few
// contiguous vectors and allocate nothing. Bit i's logit is
//   scale * clamp(intercept[i] + sum_{j in [begin[i], begin[i+1])} slope[j] x[predecessor[j]],
//                 -max_logit, max_logit) + shift[i],
// the clamp being the [clip, 1 - clip] clip and (scale, shift) the geometric tempering.
// Tabulate() then stores, for each bit with at most kMaxTabulatedPredecessors predecessors, the
// entry of each pattern: pattern = sum_j x[predecessor[begin[i] + j]] 2^j.
struct Conditionals {
  std::vector<double> intercept;
  std::vector<std::uint32_t> begin{0};
  std::vector<std::uint32_t> predecessor;
  std::vector<double> slope;
  double max_logit = 0.0;
  double scale = 1.0;
  std::vector<double> shift;
  std::vector<std::uint32_t> table_begin;  // per bit; kNotTabulated for the others
  std::vector<ConditionalEntry> table;

  static constexpr std::uint32_t kNotTabulated = std::numeric_limits<std::uint32_t>::max();

  std::size_t size() const { return intercept.size(); }

  double LogitOfPattern(std::size_t i, std::uint32_t pattern) const {
    double eta = intercept[i];
    for (std::uint32_t j = begin[i]; j < begin[i + 1]; ++j) {
      if ((pattern >> (j - begin[i])) & 1U) eta += slope[j];
    }
    return scale * std::clamp(eta, -max_logit, max_logit) + shift[i];
  }

  void Tabulate() {
    table_begin.assign(size(), kNotTabulated);
    table.clear();
    std::size_t entries = 0;
    for (std::size_t i = 0; i < size(); ++i) {
      const std::size_t s = begin[i + 1] - begin[i];
      if (s <= kMaxTabulatedPredecessors) entries += std::size_t{1} << s;
    }
    table.reserve(entries);
    for (std::size_t i = 0; i < size(); ++i) {
      const std::size_t s = begin[i + 1] - begin[i];
      if (s > kMaxTabulatedPredecessors) continue;
      table_begin[i] = static_cast<std::uint32_t>(table.size());
      for (std::uint32_t pattern = 0; pattern < (1U << s); ++pattern) {
        table.push_back(EntryOfLogit(LogitOfPattern(i, pattern)));
      }
    }
  }

  ConditionalEntry EntryOf(std::size_t i, const std::uint8_t* x) const {
    if (table_begin[i] != kNotTabulated) {
      std::uint32_t pattern = 0;
      for (std::uint32_t j = begin[i]; j < begin[i + 1]; ++j) {
        pattern |= static_cast<std::uint32_t>(x[predecessor[j]] != 0) << (j - begin[i]);
      }
      return table[table_begin[i] + pattern];
    }
    double eta = intercept[i];
    for (std::uint32_t j = begin[i]; j < begin[i + 1]; ++j) {
      if (x[predecessor[j]] != 0) eta += slope[j];
    }
    return EntryOfLogit(scale * std::clamp(eta, -max_logit, max_logit) + shift[i]);
  }
};

class LogisticProposal final : public BinaryProposal {
 public:
  // mixture_phi = 0: the (geometrically tempered) conditionals alone; in (0, 1): the joint
  // mixture (1 - mixture_phi) q_fit + mixture_phi prior.
  LogisticProposal(Conditionals conditionals, double mixture_phi, std::vector<double> prior_one)
      : conditionals_(std::move(conditionals)),
        mixture_phi_(mixture_phi),
        prior_(std::move(prior_one)) {
    COMBABC_CHECK(mixture_phi_ >= 0.0 && mixture_phi_ < 1.0);
    if (mixture_phi_ > 0.0) {
      log_fit_weight_ = std::log1p(-mixture_phi_);
      log_prior_weight_ = std::log(mixture_phi_);
    }
    conditionals_.Tabulate();
  }

  void Sample(RandomStream& rng, std::span<std::uint8_t> free_bits) const override {
    if (mixture_phi_ > 0.0 && rng.Uniform() < mixture_phi_) {
      prior_.Sample(rng, free_bits);
      return;
    }
    for (std::size_t i = 0; i < conditionals_.size(); ++i) {
      const double prob_one = conditionals_.EntryOf(i, free_bits.data()).prob_one;
      free_bits[i] = static_cast<std::uint8_t>(rng.Uniform() < prob_one);
    }
  }

  double LogDensity(std::span<const std::uint8_t> free_bits) const override {
    // log q(x) = sum_i log q(x_i | x_<i), each term read from the same entry Sample drew from; a
    // conditional made certain by tempering toward a prior of 0 or 1 gives -inf for the other
    // value, as it should.
    double fit = 0.0;
    for (std::size_t i = 0; i < conditionals_.size(); ++i) {
      fit += conditionals_.EntryOf(i, free_bits.data()).log_q[free_bits[i] != 0 ? 1 : 0];
    }
    if (mixture_phi_ == 0.0) return fit;
    return LogSumExp(log_fit_weight_ + fit, log_prior_weight_ + prior_.LogDensity(free_bits));
  }

  std::vector<double> Marginals() const override {
    const std::size_t f = conditionals_.size();
    std::vector<double> marginal(f, 0.0);
    std::vector<std::uint8_t> x(f, 0);
    const bool coupled = !conditionals_.predecessor.empty();
    for (int k = 0; coupled && k < kMarginalsDraws; ++k) {
      RandomStream rng(kMarginalsSeed, 0, static_cast<std::uint64_t>(k));
      for (std::size_t i = 0; i < f; ++i) {
        const double p = conditionals_.EntryOf(i, x.data()).prob_one;
        marginal[i] += p;
        x[i] = static_cast<std::uint8_t>(rng.Uniform() < p);
      }
    }
    const std::vector<double> prior = prior_.Marginals();
    for (std::size_t i = 0; i < f; ++i) {
      // A bit without predecessors has a constant conditional: its marginal, exactly.
      if (conditionals_.begin[i] == conditionals_.begin[i + 1]) {
        marginal[i] = conditionals_.EntryOf(i, x.data()).prob_one;
      } else {
        marginal[i] /= kMarginalsDraws;
      }
      marginal[i] = (1.0 - mixture_phi_) * marginal[i] + mixture_phi_ * prior[i];
    }
    return marginal;
  }

 private:
  Conditionals conditionals_;
  double mixture_phi_;
  double log_fit_weight_ = 0.0;
  double log_prior_weight_ = -std::numeric_limits<double>::infinity();
  IndependentBernoulliProposal prior_;
};

// The population with identical rows merged: the regressions then cost O(distinct rows), which in
// late waves is far below the population size.
struct DistinctRows {
  Eigen::MatrixXd bits;    // distinct rows x free bits, 0.0 or 1.0
  Eigen::VectorXd weight;  // summed weights, normalised to sum 1
};

DistinctRows CollapseRows(const Population& population, double total_weight) {
  const std::size_t f = population.num_free_bits;
  std::vector<std::size_t> order;
  for (std::size_t r = 0; r < population.size; ++r) {
    if (population.weights[r] > 0.0) order.push_back(r);
  }
  // Ties (equal rows) go by row index, so the summation order below, and with it every bit of
  // the fit, depends only on the population.
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const int c =
        f == 0 ? 0 : std::memcmp(population.bits_of(a).data(), population.bits_of(b).data(), f);
    return c != 0 ? c < 0 : a < b;
  });
  std::vector<std::size_t> first;  // first sorted row of each group of equal rows
  std::vector<double> weight;
  for (std::size_t s = 0; s < order.size(); ++s) {
    const bool same = s > 0 && (f == 0 || std::memcmp(population.bits_of(order[s]).data(),
                                                      population.bits_of(first.back()).data(),
                                                      f) == 0);
    if (!same) {
      first.push_back(order[s]);
      weight.push_back(0.0);
    }
    weight.back() += population.weights[order[s]];
  }
  DistinctRows rows;
  const auto n = static_cast<Eigen::Index>(first.size());
  rows.bits.resize(n, static_cast<Eigen::Index>(f));
  rows.weight.resize(n);
  for (Eigen::Index u = 0; u < n; ++u) {
    const auto bits = population.bits_of(first[static_cast<std::size_t>(u)]);
    for (std::size_t i = 0; i < f; ++i) {
      rows.bits(u, static_cast<Eigen::Index>(i)) = bits[i] ? 1.0 : 0.0;
    }
    rows.weight[u] = weight[static_cast<std::size_t>(u)] / total_weight;
  }
  return rows;
}

class LogisticKernel final : public BinaryKernel {
 public:
  explicit LogisticKernel(const LogisticKernelOptions& options) : options_(options) {
    std::string why;
    if (!options_.IsValid(&why)) throw Error(ErrorKind::kConfig, why);
  }

  std::string name() const override { return "logistic"; }

  std::unique_ptr<BinaryProposal> Fit(const Population& population,
                                      const std::vector<double>& prior_one,
                                      const Tempering& tempering) const override {
    // An empty population is the prior whatever its (unused) shape.
    if (population.size == 0) return std::make_unique<IndependentBernoulliProposal>(prior_one);
    const std::size_t f = population.num_free_bits;
    COMBABC_CHECK(prior_one.size() == f);
    COMBABC_CHECK(population.free_bits.size() == population.size * f);
    COMBABC_CHECK(population.weights.size() == population.size);
    COMBABC_CHECK(tempering.phi >= 0.0 && tempering.phi <= 1.0);
    double total_weight = 0.0;
    for (const double w : population.weights) {
      COMBABC_CHECK(std::isfinite(w) && w >= 0.0);
      total_weight += w;
    }
    // Nothing to fit, or tempered all the way: the prior (the same density both forms reach at
    // phi = 1, without rounding through the conditionals).
    if (!(total_weight > 0.0) || tempering.phi >= 1.0) {
      return std::make_unique<IndependentBernoulliProposal>(prior_one);
    }

    Conditionals conditionals = FitConditionals(CollapseRows(population, total_weight));
    double mixture_phi = 0.0;
    conditionals.shift.assign(f, 0.0);
    if (tempering.phi > 0.0 && tempering.form == TemperingForm::kGeometric) {
      // TemperedProbability's geometric form in logit space: logit q = (1 - phi) logit q_fit +
      // phi logit prior. One exp per bit per candidate instead of four pows; a prior of exactly 0
      // or 1 gives an infinite shift, i.e. the prior's value with certainty, as Eq. 3 does.
      conditionals.scale = 1.0 - tempering.phi;
      for (std::size_t i = 0; i < f; ++i) {
        conditionals.shift[i] = tempering.phi * Logit(prior_one[i]);
      }
    } else if (tempering.phi > 0.0) {
      mixture_phi = tempering.phi;
    }
    return std::make_unique<LogisticProposal>(std::move(conditionals), mixture_phi, prior_one);
  }

 private:
  Conditionals FitConditionals(const DistinctRows& rows) const {
    const Eigen::Index f = rows.bits.cols();
    const Eigen::VectorXd marginal = rows.bits.transpose() * rows.weight;
    // E_w[x_i x_k] for k < i, for the weighted correlations: the lower half of a Gram matrix.
    const Eigen::MatrixXd root_weighted = rows.weight.cwiseSqrt().asDiagonal() * rows.bits;
    Eigen::MatrixXd second = Eigen::MatrixXd::Zero(f, f);
    // (Eigen's debug assertions reject the empty product of a population without free bits.)
    if (f > 0) second.selfadjointView<Eigen::Lower>().rankUpdate(root_weighted.transpose());
    auto near_constant = [&](Eigen::Index i) {
      return std::min(marginal[i], 1.0 - marginal[i]) < options_.min_marginal ||
             !(marginal[i] > 0.0 && marginal[i] < 1.0);
    };

    Conditionals out;
    out.max_logit = Logit(1.0 - options_.clip);
    WeightedLogisticOptions regression;
    regression.ridge = options_.ridge;
    std::vector<std::pair<double, Eigen::Index>> candidates;  // (|corr|, k)
    for (Eigen::Index i = 0; i < f; ++i) {
      const double m = marginal[i];
      const double marginal_logit = Logit(std::clamp(m, options_.clip, 1.0 - options_.clip));
      candidates.clear();
      if (!near_constant(i)) {
        for (Eigen::Index k = 0; k < i; ++k) {
          if (near_constant(k)) continue;
          const double covariance = second(i, k) - m * marginal[k];
          const double corr =
              covariance / std::sqrt(m * (1.0 - m) * marginal[k] * (1.0 - marginal[k]));
          if (std::abs(corr) > options_.min_correlation) candidates.emplace_back(std::abs(corr), k);
        }
      }
      // The most correlated first (ties by index, for determinism), then back in index order so
      // that LogitOf reads x in increasing addresses.
      std::sort(candidates.begin(), candidates.end(), [](const auto& a, const auto& b) {
        return a.first != b.first ? a.first > b.first : a.second < b.second;
      });
      if (candidates.size() > static_cast<std::size_t>(options_.max_predecessors)) {
        candidates.resize(static_cast<std::size_t>(options_.max_predecessors));
      }
      std::sort(candidates.begin(), candidates.end(), [](const auto& a, const auto& b) {
        return a.second < b.second;
      });

      std::optional<Eigen::VectorXd> beta;
      if (!candidates.empty()) {
        beta = FitBit(rows, i, candidates, Logit(m), regression);
      }
      if (beta) {
        out.intercept.push_back((*beta)[0]);
        for (std::size_t j = 0; j < candidates.size(); ++j) {
          out.predecessor.push_back(static_cast<std::uint32_t>(candidates[j].second));
          out.slope.push_back((*beta)[static_cast<Eigen::Index>(j) + 1]);
        }
      } else {
        // Near-constant, uncorrelated, or a regression that failed: the marginal alone.
        out.intercept.push_back(marginal_logit);
      }
      out.begin.push_back(static_cast<std::uint32_t>(out.predecessor.size()));
    }
    return out;
  }

  // Bit i's regression on its predecessors `candidates` (index order). With few predecessors the
  // rows are first merged by their predecessors' pattern (weights summed, y the weighted fraction
  // of ones): the likelihood is the same function of the coefficients, over at most 2^s rows.
  static std::optional<Eigen::VectorXd> FitBit(
      const DistinctRows& rows,
      Eigen::Index i,
      const std::vector<std::pair<double, Eigen::Index>>& candidates,
      double marginal_logit,
      const WeightedLogisticOptions& regression) {
    const auto s = static_cast<Eigen::Index>(candidates.size());
    const Eigen::Index n = rows.bits.rows();
    Eigen::VectorXd start = Eigen::VectorXd::Zero(s + 1);
    start[0] = marginal_logit;
    if (candidates.size() > kMaxTabulatedPredecessors) {
      Eigen::MatrixXd design(n, s + 1);
      design.col(0).setOnes();
      for (Eigen::Index j = 0; j < s; ++j) {
        design.col(j + 1) = rows.bits.col(candidates[static_cast<std::size_t>(j)].second);
      }
      return FitWeightedLogistic(design, rows.bits.col(i), rows.weight, start, regression);
    }
    // Column by column: the bits are stored column-major.
    std::vector<std::uint32_t> pattern_of(static_cast<std::size_t>(n), 0);
    for (Eigen::Index j = 0; j < s; ++j) {
      const auto column = rows.bits.col(candidates[static_cast<std::size_t>(j)].second);
      for (Eigen::Index u = 0; u < n; ++u) {
        pattern_of[static_cast<std::size_t>(u)] |= static_cast<std::uint32_t>(column[u] != 0.0)
                                                   << j;
      }
    }
    std::vector<double> weight(std::size_t{1} << candidates.size(), 0.0);
    std::vector<double> ones(weight.size(), 0.0);
    for (Eigen::Index u = 0; u < n; ++u) {
      weight[pattern_of[static_cast<std::size_t>(u)]] += rows.weight[u];
      ones[pattern_of[static_cast<std::size_t>(u)]] += rows.weight[u] * rows.bits(u, i);
    }
    Eigen::Index cells = 0;
    for (const double w : weight) cells += w > 0.0 ? 1 : 0;
    Eigen::MatrixXd design(cells, s + 1);
    Eigen::VectorXd y(cells);
    Eigen::VectorXd w(cells);
    Eigen::Index c = 0;
    for (std::size_t pattern = 0; pattern < weight.size(); ++pattern) {
      if (!(weight[pattern] > 0.0)) continue;
      design(c, 0) = 1.0;
      for (Eigen::Index j = 0; j < s; ++j) design(c, j + 1) = (pattern >> j) & 1U ? 1.0 : 0.0;
      w[c] = weight[pattern];
      y[c] = ones[pattern] / weight[pattern];
      ++c;
    }
    return FitWeightedLogistic(design, y, w, start, regression);
  }

  LogisticKernelOptions options_;
};

}  // namespace

std::unique_ptr<BinaryKernel> MakeLogisticKernel(const LogisticKernelOptions& options) {
  return std::make_unique<LogisticKernel>(options);
}

}  // namespace combabc
