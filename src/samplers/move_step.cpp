#include "samplers/move_step.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "combabc/core/check.hpp"
#include "combabc/core/error.hpp"
#include "combabc/samplers/run_history.hpp"

namespace combabc {
namespace {

// Beyond this many free bits the second bit of a pair is drawn like the first, not by its
// correlation with it: the table of f x f weights would cost 8 f^2 bytes (the pair correlations'
// own limit, run_history.hpp).
constexpr std::size_t kMaxPairTableBits = kMaxPairCorrelationBits;

// Cumulative sums of `w`, in place.
void Accumulate(std::vector<double>& w) {
  double sum = 0.0;
  for (double& x : w) {
    sum += x;
    x = sum;
  }
}

}  // namespace

std::vector<std::size_t> SystematicResample(std::span<const double> weights,
                                            std::size_t n,
                                            double u) {
  double total = 0.0;
  for (double w : weights) total += w;
  COMBABC_CHECK(total > 0.0 && !weights.empty());
  std::vector<std::size_t> out;
  out.reserve(n);
  double cumulative = weights[0] / total;
  std::size_t i = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const double point = (static_cast<double>(k) + u) / static_cast<double>(n);
    while (point >= cumulative && i + 1 < weights.size()) {
      ++i;
      cumulative += weights[i] / total;
    }
    out.push_back(i);
  }
  return out;
}

double EffectiveSampleSize(std::span<const double> weights) {
  double sum = 0.0;
  double squares = 0.0;
  for (double w : weights) {
    sum += w;
    squares += w * w;
  }
  return squares > 0.0 ? sum * sum / squares : 0.0;
}

EssStep StepKeepingEss(const std::function<std::vector<double>(double)>& weights_at,
                       double wanted) {
  if (EffectiveSampleSize(weights_at(1.0)) >= wanted) return {};
  double lo = 0.0;
  double hi = 1.0;
  if (EffectiveSampleSize(weights_at(lo)) < wanted) return {0.0, 0.0};
  for (int i = 0; i < 40; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (EffectiveSampleSize(weights_at(mid)) >= wanted) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  return {lo, hi};
}

int RoundsNeeded(double rate, double stay, int max_rounds) {
  if (!(rate > 0.0)) return max_rounds;
  if (rate >= 1.0) return 1;
  const double rounds = std::ceil(std::log(stay) / std::log1p(-rate));
  return static_cast<int>(std::clamp(rounds, 1.0, static_cast<double>(max_rounds)));
}

MoveProposals::MoveProposals(const Population& population,
                             const ParameterSpace& space,
                             const JointProposal* fitted,
                             const JointProposal* ancestor,
                             double independent_share)
    : space_(space),
      fitted_(fitted ? fitted : ancestor),
      ancestor_(fitted ? ancestor : nullptr),
      independent_share_(fitted_ ? independent_share : 0.0),
      f_(population.num_free_bits),
      r_(population.num_reals) {
  // The population's P(bit = 1) and, for the pair table, its moments.
  const std::size_t n = population.size;
  std::vector<double> one(f_, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    const auto bits = population.bits_of(i);
    for (std::size_t j = 0; j < f_; ++j) one[j] += population.weights[i] * bits[j];
  }
  // A bit the particles agree on is flipped rarely but not never: its weight is at least that of
  // one particle in 2n disagreeing.
  const double floor = 0.5 / static_cast<double>(std::max<std::size_t>(n, 1));
  first_.resize(f_);
  for (std::size_t j = 0; j < f_; ++j) first_[j] = std::max(std::min(one[j], 1.0 - one[j]), floor);
  if (f_ >= 2 && f_ <= kMaxPairTableBits) {
    // The second bit by |correlation| with the first (plus a floor, so every pair is possible).
    std::vector<double> both(f_ * f_, 0.0);
    for (std::size_t i = 0; i < n; ++i) {
      const auto bits = population.bits_of(i);
      const double w = population.weights[i];
      for (std::size_t j = 0; j < f_; ++j) {
        if (!bits[j]) continue;
        for (std::size_t k = 0; k < f_; ++k) both[j * f_ + k] += w * bits[k];
      }
    }
    second_.assign(f_ * f_, 0.0);
    for (std::size_t j = 0; j < f_; ++j) {
      for (std::size_t k = 0; k < f_; ++k) {
        if (k == j) continue;
        const double var = one[j] * (1.0 - one[j]) * one[k] * (1.0 - one[k]);
        const double cov = both[j * f_ + k] - one[j] * one[k];
        const double corr = var > 0.0 ? std::abs(cov) / std::sqrt(var) : 0.0;
        second_[j * f_ + k] = corr + 0.1;
      }
      std::vector<double> row(second_.begin() + static_cast<std::ptrdiff_t>(j * f_),
                              second_.begin() + static_cast<std::ptrdiff_t>((j + 1) * f_));
      Accumulate(row);
      std::copy(row.begin(), row.end(), second_.begin() + static_cast<std::ptrdiff_t>(j * f_));
    }
  }
  Accumulate(first_);
  // The random walk: the particles' standard deviation per real, scaled by 2.38 / sqrt(r)
  // (Roberts, Gelman & Gilks 1997), never 0 so that a collapsed real can still move.
  step_.assign(r_, 0.0);
  if (r_ > 0) {
    std::vector<double> mean(r_, 0.0);
    for (std::size_t i = 0; i < n; ++i) {
      const auto x = population.reals_of(i);
      for (std::size_t k = 0; k < r_; ++k) mean[k] += population.weights[i] * x[k];
    }
    for (std::size_t i = 0; i < n; ++i) {
      const auto x = population.reals_of(i);
      for (std::size_t k = 0; k < r_; ++k) {
        step_[k] += population.weights[i] * (x[k] - mean[k]) * (x[k] - mean[k]);
      }
    }
    const double scale = 2.38 / std::sqrt(static_cast<double>(r_));
    for (std::size_t k = 0; k < r_; ++k) {
      step_[k] = scale * std::max(std::sqrt(step_[k]), 1e-6 * std::max(1.0, std::abs(mean[k])));
    }
  }
}

std::size_t MoveProposals::Draw(RandomStream& rng, std::span<const double> cumulative) const {
  const double u = rng.Uniform() * cumulative.back();
  const auto it = std::upper_bound(cumulative.begin(), cumulative.end(), u);
  return std::min(static_cast<std::size_t>(it - cumulative.begin()), cumulative.size() - 1);
}

MoveProposal MoveProposals::Propose(RandomStream& rng,
                                    std::span<const std::uint8_t> free,
                                    std::span<const double> reals,
                                    std::span<std::uint8_t> new_free,
                                    std::span<double> new_reals) const {
  MoveProposal move;
  if (independent_share_ > 0.0 && rng.Uniform() < independent_share_) {
    move.independent = true;
    const JointProposal& q = ancestor_ && rng.Uniform() < 0.5 ? *ancestor_ : *fitted_;
    q.Sample(rng, new_free, new_reals);
    move.log_q_ratio = q.LogDensity(free, reals) - q.LogDensity(new_free, new_reals);
    return move;
  }
  std::copy(free.begin(), free.end(), new_free.begin());
  std::copy(reals.begin(), reals.end(), new_reals.begin());
  const bool flip = f_ > 0 && (r_ == 0 || rng.Uniform() < 0.5);
  if (flip) {
    const std::size_t j = Draw(rng, first_);
    new_free[j] ^= 1;
    if (f_ >= 2 && rng.Uniform() < 0.5) {
      std::size_t k = j;
      while (k == j) {
        k = second_.empty() ? Draw(rng, first_)
                            : Draw(rng, std::span<const double>(second_.data() + j * f_, f_));
      }
      new_free[k] ^= 1;
    }
    return move;
  }
  for (std::size_t k = 0; k < r_; ++k) new_reals[k] += step_[k] * rng.Normal();
  move.outside_prior = space_.LogPriorReals(new_reals) == -std::numeric_limits<double>::infinity();
  return move;
}

}  // namespace combabc
