#include "combabc/proposals/ancestor_kernel.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "combabc/core/check.hpp"
#include "combabc/core/error.hpp"
#include "combabc/proposals/independent_kernel.hpp"
#include "combabc/proposals/proposal_options.hpp"
#include "proposals/gaussian_factor.hpp"

namespace combabc {
namespace {

constexpr double kMinusInfinity = -std::numeric_limits<double>::infinity();
// The defensive weight of the prior (ancestor_kernel.hpp).
constexpr double kDefensive = 0.05;
// The flip rates' floor, times the number of free bits: the expected number of flips of bits the
// population holds fixed, per candidate.
constexpr double kMinFlips = 0.1;
// LogDensity's scratch for up to this many reals is on the stack.
constexpr std::size_t kStackReals = 16;
// A bit pattern's particles make its own covariance from this effective sample size on.
constexpr double kMinPatternEss = 10.0;

// Adds exp(term) to a running log-sum-exp (max, sum): one pass, no overflow.
struct LogSum {
  double max = kMinusInfinity, sum = 0.0;
  void Add(double term) {
    if (term == kMinusInfinity) return;
    if (term <= max) {
      sum += std::exp(term - max);
    } else {
      sum = sum * std::exp(max - term) + 1.0;
      max = term;
    }
  }
  double Value() const { return max == kMinusInfinity ? max : max + std::log(sum); }
};

// One distinct free-bit pattern of the population and its particles (those of positive weight).
struct Pattern {
  std::vector<std::uint8_t> bits;
  double log_weight = 0.0;         // log of the pattern's total weight
  std::size_t first = 0, end = 0;  // its particles: [first, end) of the proposal's arrays
  std::size_t factor = 0;          // the Gaussian factor of its particles
};

class AncestorProposal final : public JointProposal {
 public:
  // The prior alone (wave 0, an empty population).
  explicit AncestorProposal(const ParameterSpace& space)
      : f_(static_cast<std::size_t>(space.num_free_bits())),
        r_(static_cast<std::size_t>(space.num_reals())),
        defensive_(1.0),
        prior_bits_(space.binary().free_prior_one()),
        prior_one_(space.binary().free_prior_one()),
        prior_reals_(space.reals_prior()),
        box_(SupportBox(prior_reals_)) {}

  AncestorProposal(const Population& population,
                   const ParameterSpace& space,
                   double scale,
                   double defensive)
      : AncestorProposal(space) {
    defensive_ = defensive;
    FitBits(population);
    FitPatterns(population, space, scale);
  }

  void Sample(RandomStream& rng,
              std::span<std::uint8_t> free_bits,
              std::span<double> reals) const override {
    COMBABC_CHECK(free_bits.size() == f_ && reals.size() == r_);
    std::array<double, kStackReals> stack{};
    std::vector<double> heap(truncate_ && r_ > kStackReals ? r_ : 0);
    const std::span<double> z(r_ > kStackReals ? heap.data() : stack.data(), truncate_ ? r_ : 0);
    for (int attempt = 0; attempt < kMaxSupportTries; ++attempt) {
      if (patterns_.empty() || rng.Uniform() < defensive_) {
        prior_bits_.Sample(rng, free_bits);
        prior_reals_.Sample(rng, reals);
        return;
      }
      // Ancestor j with probability w_j: the first cumulative weight above u x total.
      const double u = rng.Uniform() * cumulative_.back();
      const std::size_t j = std::min<std::size_t>(
          std::upper_bound(cumulative_.begin(), cumulative_.end(), u) - cumulative_.begin(),
          cumulative_.size() - 1);
      const Pattern& g = patterns_[pattern_of_[j]];
      for (std::size_t i = 0; i < f_; ++i) {
        free_bits[i] = static_cast<std::uint8_t>(g.bits[i] ^ (rng.Bernoulli53(flip_[i]) ? 1 : 0));
      }
      // Inside the bounds by construction when truncated (SampleInBox); else redrawn whole.
      if (truncate_) {
        SampleInBox(factors_[g.factor], centres_.data() + j * r_, box_, rng, reals, z);
      } else {
        SampleGaussian(factors_[g.factor], centres_.data() + j * r_, rng, reals);
      }
      if (InSupport(reals)) return;
    }
    throw Error(ErrorKind::kSoftware,
                "ancestor proposal: " + std::to_string(kMaxSupportTries) +
                    " draws in a row fell outside the prior support of the reals; the kernel has "
                    "almost no mass where the joint prior's density is positive");
  }

  double LogDensity(std::span<const std::uint8_t> free_bits,
                    std::span<const double> reals) const override {
    COMBABC_CHECK(free_bits.size() == f_ && reals.size() == r_);
    if (!InSupport(reals)) return kMinusInfinity;
    LogSum sum;
    sum.Add(log_defensive_ + LogPrior(free_bits, reals));
    if (patterns_.empty()) return sum.Value();
    // L_g^{-1} (r - c_first) on the stack (no allocation per candidate) unless r is large.
    std::array<double, kStackReals> stack{};
    std::vector<double> heap(r_ > kStackReals ? r_ : 0);
    double* y = r_ > kStackReals ? heap.data() : stack.data();
    for (const Pattern& g : patterns_) {
      const double bits = log_ancestors_ + LogFlips(g, free_bits);
      if (bits == kMinusInfinity) continue;
      // L_g^{-1} (r - c_first); the particles' whitened offsets are precomputed, so that each
      // costs O(r) here and nothing cancels when the reals are large with a small spread.
      const Factor& l = factors_[g.factor];
      const double* c0 = centres_.data() + g.first * r_;
      for (std::size_t i = 0; i < r_; ++i) {
        double v = 0.0;
        for (std::size_t k = 0; k <= i; ++k) v += l.l_inv[Tri(i, k)] * (reals[k] - c0[k]);
        y[i] = v;
      }
      for (std::size_t j = g.first; j < g.end; ++j) {
        const double* w = whitened_.data() + j * r_;
        double q = 0.0;
        for (std::size_t i = 0; i < r_; ++i) q += (y[i] - w[i]) * (y[i] - w[i]);
        sum.Add(bits + log_normal_[j] - 0.5 * q -
                (truncate_ ? LogBoxMass(l, box_, reals, y, w) : 0.0));
      }
    }
    return sum.Value();
  }

  double LogBitsDensity(std::span<const std::uint8_t> free_bits) const override {
    COMBABC_CHECK(free_bits.size() == f_);
    LogSum sum;
    sum.Add(log_defensive_ + prior_bits_.LogDensity(free_bits));
    for (const Pattern& g : patterns_) {
      sum.Add(log_ancestors_ + g.log_weight + LogFlips(g, free_bits));
    }
    return sum.Value();
  }

  // P(b_i = 1) = (1 - a) sum_g W_g (b_gi (1 - e_i) + (1 - b_gi) e_i) + a prior_i: exact.
  std::vector<double> Marginals() const override {
    std::vector<double> m(prior_one_);
    for (double& x : m) x *= defensive_;
    for (const Pattern& g : patterns_) {
      const double w = (1.0 - defensive_) * std::exp(g.log_weight);
      for (std::size_t i = 0; i < f_; ++i) {
        const double e = flip_rate_[i];
        m[i] += w * (g.bits[i] ? 1.0 - e : e);
      }
    }
    return m;
  }

 private:
  // Flip rates from the weighted marginals (ancestor_kernel.hpp).
  void FitBits(const Population& population) {
    std::vector<double> m(f_, 0.0);
    for (std::size_t j = 0; j < population.size; ++j) {
      const auto bits = population.bits_of(j);
      for (std::size_t i = 0; i < f_; ++i) m[i] += bits[i] ? population.weights[j] : 0.0;
    }
    // A bit whose prior is 0 or 1 (a fixed or dummy bit) is never flipped: every particle of
    // positive weight holds its one possible value, and a flip would only propose candidates of
    // prior 0, accepted for nothing (weight 0). The floor spreads over the other bits.
    const auto uncertain = [&](std::size_t i) {
      return prior_one_[i] > 0.0 && prior_one_[i] < 1.0;
    };
    std::size_t movable = 0;
    for (std::size_t i = 0; i < f_; ++i) movable += uncertain(i) ? 1 : 0;
    const double floor =
        std::min(0.5, kMinFlips / static_cast<double>(std::max<std::size_t>(movable, 1)));
    for (std::size_t i = 0; i < f_; ++i) {
      const double e = uncertain(i) ? std::clamp(std::min(m[i], 1.0 - m[i]), floor, 0.5) : 0.0;
      flip_rate_.push_back(e);
      flip_.push_back(BernoulliThreshold(e));
      log_keep_.push_back(std::log1p(-e));
      log_flip_.push_back(std::log(e));
    }
  }

  // Groups the particles of positive weight by bit pattern, in order of first appearance, and
  // fits each pattern's Gaussian factor.
  void FitPatterns(const Population& population, const ParameterSpace& space, double scale) {
    std::map<std::vector<std::uint8_t>, std::vector<std::size_t>> members;
    std::vector<const std::vector<std::uint8_t>*> order;
    double total = 0.0;
    for (std::size_t j = 0; j < population.size; ++j) {
      if (!(population.weights[j] > 0.0)) continue;
      total += population.weights[j];
      const auto bits = population.bits_of(j);
      auto [it, added] = members.try_emplace({bits.begin(), bits.end()});
      if (added) order.push_back(&it->first);
      it->second.push_back(j);
    }
    if (!(total > 0.0)) {
      defensive_ = 1.0;  // nothing to descend from: the prior
      return;
    }
    const std::vector<double> prior_sd = PriorSd(space);
    // factors_[0], the whole population's (without reals: an empty factor, log det 0).
    factors_.push_back(r_ > 0 ? Factorise(scale * Covariance(population, AllOf(members)), prior_sd)
                              : Factor{});
    for (const auto* bits : order) {
      const std::vector<std::size_t>& js = members.at(*bits);
      Pattern g;
      g.bits = *bits;
      g.first = cumulative_.size();
      double w = 0.0, w2 = 0.0;
      for (const std::size_t j : js) {
        const double wj = population.weights[j] / total;
        w += wj;
        w2 += wj * wj;
        const auto reals = population.reals_of(j);
        centres_.insert(centres_.end(), reals.begin(), reals.end());
        cumulative_.push_back((cumulative_.empty() ? 0.0 : cumulative_.back()) + wj);
        pattern_of_.push_back(patterns_.size());
        log_normal_.push_back(std::log(wj));
      }
      g.end = cumulative_.size();
      g.log_weight = std::log(w);
      if (r_ > 0 && w * w / w2 >= kMinPatternEss) {
        g.factor = factors_.size();
        factors_.push_back(Factorise(scale * Covariance(population, js), prior_sd));
      }
      patterns_.push_back(std::move(g));
    }
    for (const Pattern& g : patterns_) {
      const Factor& l = factors_[g.factor];
      const double* c0 = centres_.data() + g.first * r_;
      for (std::size_t j = g.first; j < g.end; ++j) {
        // log w_j - (r/2) log 2 pi - log det L_g, and L_g^{-1} (c_j - c_first).
        log_normal_[j] -= static_cast<double>(r_) * kLogRootTwoPi + l.log_det;
        for (std::size_t i = 0; i < r_; ++i) {
          double v = 0.0;
          for (std::size_t k = 0; k <= i; ++k) {
            v += l.l_inv[Tri(i, k)] * (centres_[j * r_ + k] - c0[k]);
          }
          whitened_.push_back(v);
        }
      }
    }
    log_defensive_ = std::log(defensive_);
    log_ancestors_ = std::log1p(-defensive_);
    truncate_ = r_ > 0 && TruncateEachCoordinate(
                              cumulative_,
                              centres_,
                              [&](std::size_t j) -> const Factor& {
                                return factors_[patterns_[pattern_of_[j]].factor];
                              },
                              box_);
  }

  static std::vector<std::size_t> AllOf(
      const std::map<std::vector<std::uint8_t>, std::vector<std::size_t>>& members) {
    std::vector<std::size_t> all;
    for (const auto& [bits, js] : members) all.insert(all.end(), js.begin(), js.end());
    return all;
  }

  // The weighted covariance of the reals of particles `js` (weights renormalised over them).
  Eigen::MatrixXd Covariance(const Population& population,
                             const std::vector<std::size_t>& js) const {
    const auto r = static_cast<Eigen::Index>(r_);
    Eigen::VectorXd mean = Eigen::VectorXd::Zero(r);
    double total = 0.0;
    for (const std::size_t j : js) {
      total += population.weights[j];
      mean += population.weights[j] *
              Eigen::Map<const Eigen::VectorXd>(population.reals_of(j).data(), r);
    }
    mean /= total;
    Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(r, r);
    for (const std::size_t j : js) {
      const Eigen::VectorXd d =
          Eigen::Map<const Eigen::VectorXd>(population.reals_of(j).data(), r) - mean;
      cov += (population.weights[j] / total) * d * d.transpose();
    }
    return cov;
  }

  // log F(b | b_g): the flips that turn the pattern into `free_bits`.
  double LogFlips(const Pattern& g, std::span<const std::uint8_t> free_bits) const {
    double sum = 0.0;
    for (std::size_t i = 0; i < f_; ++i) {
      sum += ((free_bits[i] & 1U) == g.bits[i]) ? log_keep_[i] : log_flip_[i];
    }
    return sum;
  }

  double LogPrior(std::span<const std::uint8_t> free_bits, std::span<const double> reals) const {
    return prior_bits_.LogDensity(free_bits) + prior_reals_.LogDensity(reals);
  }

  bool InSupport(std::span<const double> reals) const { return prior_reals_.InSupport(reals); }

  std::size_t f_, r_;
  double defensive_;
  double log_defensive_ = 0.0, log_ancestors_ = kMinusInfinity;
  BernoulliProposal prior_bits_;
  std::vector<double> prior_one_;
  RealsPrior prior_reals_;  // a copy: the proposal may outlive the space
  Box box_;                 // the reals' bounds
  bool truncate_ = false;   // each Gaussian truncated to box_ (TruncateEachCoordinate)
  std::vector<double> flip_rate_, log_keep_, log_flip_;
  std::vector<std::uint64_t> flip_;  // BernoulliThreshold(flip_rate_)
  std::vector<Pattern> patterns_;
  std::vector<Factor> factors_;  // [0]: the whole population's
  // Per particle of positive weight, grouped by pattern: reals (N x r), running sums of the
  // weights, pattern, log w_j - (r/2) log 2 pi - log det L, whitened offsets (N x r).
  std::vector<double> centres_, cumulative_;
  std::vector<std::size_t> pattern_of_;
  std::vector<double> log_normal_, whitened_;
};

class AncestorKernel final : public JointKernel {
 public:
  explicit AncestorKernel(double scale) : scale_(scale) {}
  std::string name() const override { return ToString(BinaryKernelKind::kAncestor); }

  std::unique_ptr<JointProposal> Prior(const ParameterSpace& space) const override {
    return std::make_unique<AncestorProposal>(space);
  }

  std::unique_ptr<JointProposal> Fit(const Population& population,
                                     const ParameterSpace& space,
                                     const Tempering& tempering) const override {
    COMBABC_CHECK(population.num_free_bits == static_cast<std::size_t>(space.num_free_bits()));
    COMBABC_CHECK(population.num_reals == static_cast<std::size_t>(space.num_reals()));
    if (population.size == 0) return Prior(space);
    return std::make_unique<AncestorProposal>(
        population, space, scale_, std::clamp(tempering.phi, kDefensive, 1.0));
  }

 private:
  double scale_;
};

}  // namespace

std::unique_ptr<JointKernel> MakeAncestorKernel(double scale) {
  if (!(scale > 0.0) || !std::isfinite(scale)) {
    throw Error(ErrorKind::kConfig,
                "ProposalOptions::scale = " + std::to_string(scale) + "; must be finite and > 0");
  }
  return std::make_unique<AncestorKernel>(scale);
}

}  // namespace combabc
