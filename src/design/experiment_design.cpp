#include "combabc/design/experiment_design.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "combabc/core/thread_pool.hpp"
#include "combabc/rng/random_stream.hpp"

namespace combabc::design {
namespace {

// Stream keys: truth j draws from (seed, kTruthStream, j); its noise for candidate c from
// (seed, kNoiseStream + c, j).
constexpr std::uint64_t kTruthStream = 0xD5'0000'0000ULL;
constexpr std::uint64_t kNoiseStream = 0xD6'0000'0000ULL;

double BinaryEntropy(double p) {
  if (!(p > 0.0) || !(p < 1.0)) return 0.0;
  return -(p * std::log2(p) + (1.0 - p) * std::log2(1.0 - p));
}

// What one truth's posterior says.
struct TruthOutcome {
  double entropy = 0.0;
  double effective = 0.0;
  int identified = 0;
  int wrong = 0;
  std::vector<double> decided;  // |2 p_k - 1|
};

class Scorer {
 public:
  Scorer(const Population& population,
         const std::vector<CandidateProfiles>& candidates,
         const DesignOptions& options)
      : pop_(population), candidates_(candidates), options_(options) {
    const std::size_t n = pop_.size();
    log_weight_.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      log_weight_[i] = pop_.weights[i] > 0.0 ? std::log(pop_.weights[i])
                                             : -std::numeric_limits<double>::infinity();
    }
    // Truths by weight (inverse CDF of one uniform each).
    std::vector<double> cdf(n);
    double total = 0.0;
    for (std::size_t i = 0; i < n; ++i) cdf[i] = total += pop_.weights[i];
    for (int j = 0; j < options_.truths; ++j) {
      RandomStream rng(options_.seed, kTruthStream, static_cast<std::uint64_t>(j));
      const double u = rng.Uniform() * total;
      const auto it = std::upper_bound(cdf.begin(), cdf.end(), u);
      truth_.push_back(std::min<std::size_t>(static_cast<std::size_t>(it - cdf.begin()), n - 1));
    }
  }

  // log p(y_jc | particle i) up to a constant, for every particle.
  void LogLikelihood(int c, int j, std::span<double> out) const {
    const CandidateProfiles& profiles = candidates_[static_cast<std::size_t>(c)];
    const auto m = static_cast<std::size_t>(profiles.points);
    std::vector<double> y(profiles.values.begin() + static_cast<std::ptrdiff_t>(truth_[j] * m),
                          profiles.values.begin() + static_cast<std::ptrdiff_t>(truth_[j] * m + m));
    RandomStream rng(
        options_.seed, kNoiseStream + static_cast<std::uint64_t>(c), static_cast<std::uint64_t>(j));
    for (double& v : y) v += options_.noise_sigma * rng.Normal();
    const double scale = 1.0 / (2.0 * options_.noise_sigma * options_.noise_sigma);
    for (std::size_t i = 0; i < pop_.size(); ++i) {
      const double* yi = profiles.values.data() + i * m;
      double sse = 0.0;
      for (std::size_t k = 0; k < m; ++k) {
        const double r = y[k] - yi[k];
        sse += r * r;
      }
      out[i] = -sse * scale;
    }
  }

  // The posterior of truth j given the log-likelihood `ll` of its data.
  TruthOutcome Outcome(int j, std::span<const double> ll) const {
    const std::size_t n = pop_.size();
    const auto d = static_cast<std::size_t>(pop_.dimension);
    double top = -std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < n; ++i) top = std::max(top, log_weight_[i] + ll[i]);
    std::vector<double> p(d, 0.0);
    double total = 0.0, squares = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      const double w = std::exp(log_weight_[i] + ll[i] - top);
      if (w == 0.0) continue;
      total += w;
      squares += w * w;
      const std::uint8_t* b = pop_.bits.data() + i * d;
      for (std::size_t k = 0; k < d; ++k) p[k] += b[k] ? w : 0.0;
    }
    TruthOutcome o;
    o.effective = total * total / squares;
    o.decided.resize(d);
    const std::uint8_t* truth = pop_.bits.data() + truth_[static_cast<std::size_t>(j)] * d;
    for (std::size_t k = 0; k < d; ++k) {
      p[k] /= total;
      o.entropy += BinaryEntropy(p[k]);
      o.decided[k] = std::abs(2.0 * p[k] - 1.0);
      if (std::abs(p[k] - 0.5) > options_.identified_margin) {
        ++o.identified;
        if ((p[k] > 0.5) != (truth[k] != 0)) ++o.wrong;
      }
    }
    return o;
  }

  // The score of experiments `chosen` plus `extra` (-1: none), given base[j] = the summed
  // log-likelihood of `chosen` for truth j (empty: none chosen).
  Score Evaluate(const std::vector<std::vector<double>>& base,
                 int extra,
                 ThreadPool& pool,
                 double prior_entropy) const {
    const auto truths = static_cast<std::size_t>(options_.truths);
    std::vector<TruthOutcome> outcomes(truths);
    pool.ParallelFor(truths, 4, [&](std::size_t begin, std::size_t end) {
      std::vector<double> ll(pop_.size());
      for (std::size_t j = begin; j < end; ++j) {
        if (extra >= 0) {
          LogLikelihood(extra, static_cast<int>(j), ll);
        } else {
          std::fill(ll.begin(), ll.end(), 0.0);
        }
        if (!base.empty()) {
          for (std::size_t i = 0; i < ll.size(); ++i) ll[i] += base[j][i];
        }
        outcomes[j] = Outcome(static_cast<int>(j), ll);
      }
    });
    // Summed in truth order: the same result for any number of threads.
    Score s;
    s.identifiability.assign(static_cast<std::size_t>(pop_.dimension), 0.0);
    double sum = 0.0, sum2 = 0.0;
    for (const TruthOutcome& o : outcomes) {
      const double gain = prior_entropy - o.entropy;
      sum += gain;
      sum2 += gain * gain;
      s.identified += o.identified;
      s.wrong += o.wrong;
      s.effective_particles += o.effective;
      for (std::size_t k = 0; k < o.decided.size(); ++k) s.identifiability[k] += o.decided[k];
    }
    const auto m = static_cast<double>(truths);
    s.information_gain = sum / m;
    const double variance = std::max(0.0, sum2 / m - s.information_gain * s.information_gain);
    s.information_gain_se = truths > 1 ? std::sqrt(variance / (m - 1.0)) : 0.0;
    s.identified /= m;
    s.wrong /= m;
    s.effective_particles /= m;
    for (double& v : s.identifiability) v /= m;
    return s;
  }

 private:
  const Population& pop_;
  const std::vector<CandidateProfiles>& candidates_;
  const DesignOptions& options_;
  std::vector<double> log_weight_;
  std::vector<std::size_t> truth_;
};

void Check(const Population& population,
           const std::vector<CandidateProfiles>& candidates,
           const DesignOptions& options) {
  auto fail = [](const std::string& why) { throw std::invalid_argument("design: " + why); };
  if (population.dimension < 1 || population.size() == 0) fail("empty population");
  if (population.bits.size() !=
      population.size() * static_cast<std::size_t>(population.dimension)) {
    fail("population bits must be size() x dimension");
  }
  for (double w : population.weights) {
    if (!(w >= 0.0) || !std::isfinite(w)) fail("population weights must be finite and >= 0");
  }
  if (candidates.empty()) fail("no candidates");
  for (const CandidateProfiles& c : candidates) {
    if (c.points < 1 || c.values.size() != population.size() * static_cast<std::size_t>(c.points)) {
      fail("candidate profiles must be size() x points");
    }
  }
  if (!(options.noise_sigma > 0.0) || !std::isfinite(options.noise_sigma)) {
    fail("noise_sigma must be finite and > 0");
  }
  if (options.truths < 2) fail("truths must be >= 2");
  if (options.select < 1) fail("select must be >= 1");
  if (!(options.identified_margin >= 0.0 && options.identified_margin < 0.5)) {
    fail("identified_margin must be in [0, 0.5)");
  }
}

}  // namespace

std::vector<double> Marginals(const Population& population) {
  const auto d = static_cast<std::size_t>(population.dimension);
  std::vector<double> p(d, 0.0);
  double total = 0.0;
  for (std::size_t i = 0; i < population.size(); ++i) {
    total += population.weights[i];
    for (std::size_t k = 0; k < d; ++k) {
      if (population.bits[i * d + k]) p[k] += population.weights[i];
    }
  }
  for (double& v : p) v = total > 0.0 ? v / total : 0.0;
  return p;
}

double MarginalEntropy(std::span<const double> marginals) {
  double h = 0.0;
  for (double p : marginals) h += BinaryEntropy(p);
  return h;
}

DesignResult ScoreCandidates(const Population& population,
                             const std::vector<CandidateProfiles>& candidates,
                             const DesignOptions& options) {
  Check(population, candidates, options);
  ThreadPool pool(options.threads);
  const Scorer scorer(population, candidates, options);
  DesignResult result;
  const std::vector<double> prior = Marginals(population);
  result.prior_entropy = MarginalEntropy(prior);
  for (double p : prior) result.prior_identified += std::abs(p - 0.5) > options.identified_margin;

  const int count = static_cast<int>(candidates.size());
  const std::vector<std::vector<double>> none;
  for (int c = 0; c < count; ++c) {
    result.scores.push_back(scorer.Evaluate(none, c, pool, result.prior_entropy));
  }
  // Greedy: each step keeps the chosen experiments' summed log-likelihood per truth.
  const auto truths = static_cast<std::size_t>(options.truths);
  std::vector<std::vector<double>> base;
  std::vector<bool> taken(static_cast<std::size_t>(count), false);
  for (int step = 0; step < std::min(options.select, count); ++step) {
    int best = -1;
    Score best_score;
    for (int c = 0; c < count; ++c) {
      if (taken[static_cast<std::size_t>(c)]) continue;
      Score s = step == 0 ? result.scores[static_cast<std::size_t>(c)]
                          : scorer.Evaluate(base, c, pool, result.prior_entropy);
      // Ties go to the earlier candidate: the order of the grid decides, not the threads.
      if (best < 0 || s.information_gain > best_score.information_gain) {
        best = c;
        best_score = std::move(s);
      }
    }
    taken[static_cast<std::size_t>(best)] = true;
    result.selected.push_back(best);
    result.cumulative.push_back(best_score);
    if (base.empty()) base.assign(truths, std::vector<double>(population.size(), 0.0));
    pool.ParallelFor(truths, 4, [&](std::size_t begin, std::size_t end) {
      std::vector<double> ll(population.size());
      for (std::size_t j = begin; j < end; ++j) {
        scorer.LogLikelihood(best, static_cast<int>(j), ll);
        for (std::size_t i = 0; i < ll.size(); ++i) base[j][i] += ll[i];
      }
    });
  }
  return result;
}

}  // namespace combabc::design
