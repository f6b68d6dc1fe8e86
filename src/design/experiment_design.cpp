#include "combabc/design/experiment_design.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
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

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kMinusInf = -std::numeric_limits<double>::infinity();

// What one truth's posterior says.
struct TruthOutcome {
  double entropy = 0.0;
  double effective = 0.0;
  int identified = 0;
  int wrong = 0;
  std::vector<double> decided;  // |2 p_k - 1|
  std::vector<double> signal;   // per bit: the flip's log-likelihood ratio (NaN: unknown)
};

// The truth's noisy data under candidate c: its profile plus noise from (seed, c, j).
std::vector<double> TruthData(const CandidateProfiles& profiles,
                              std::size_t row,
                              int c,
                              int j,
                              const DesignOptions& options) {
  const auto m = static_cast<std::size_t>(profiles.points);
  std::vector<double> y(profiles.values.begin() + static_cast<std::ptrdiff_t>(row * m),
                        profiles.values.begin() + static_cast<std::ptrdiff_t>(row * m + m));
  RandomStream rng(
      options.seed, kNoiseStream + static_cast<std::uint64_t>(c), static_cast<std::uint64_t>(j));
  for (double& v : y) v += options.noise_sigma * rng.Normal();
  return y;
}

double SquaredDistance(const CandidateProfiles& profiles, std::size_t a, std::size_t b) {
  const auto m = static_cast<std::size_t>(profiles.points);
  double sse = 0.0;
  for (std::size_t k = 0; k < m; ++k) {
    const double r = profiles.values[a * m + k] - profiles.values[b * m + k];
    sse += r * r;
  }
  return sse;
}

// The truths' outcomes averaged, in truth order: the same result for any number of threads.
Score Aggregate(const std::vector<TruthOutcome>& outcomes, int dimension, double prior_entropy) {
  Score s;
  const auto d = static_cast<std::size_t>(dimension);
  s.identifiability.assign(d, 0.0);
  s.flip_signal.assign(d, 0.0);
  std::vector<int> signals(d, 0);
  double sum = 0.0, sum2 = 0.0;
  for (const TruthOutcome& o : outcomes) {
    const double gain = prior_entropy - o.entropy;
    sum += gain;
    sum2 += gain * gain;
    s.identified += o.identified;
    s.wrong += o.wrong;
    s.effective_particles += o.effective;
    for (std::size_t k = 0; k < d; ++k) s.identifiability[k] += o.decided[k];
    for (std::size_t k = 0; k < o.signal.size(); ++k) {
      if (std::isfinite(o.signal[k])) {
        s.flip_signal[k] += o.signal[k];
        ++signals[k];
      }
    }
  }
  const auto m = static_cast<double>(outcomes.size());
  s.information_gain = sum / m;
  const double variance = std::max(0.0, sum2 / m - s.information_gain * s.information_gain);
  s.information_gain_se = outcomes.size() > 1 ? std::sqrt(variance / (m - 1.0)) : 0.0;
  s.identified /= m;
  s.wrong /= m;
  s.effective_particles /= m;
  for (double& v : s.identifiability) v /= m;
  for (std::size_t k = 0; k < d; ++k) {
    s.flip_signal[k] = signals[k] > 0 ? s.flip_signal[k] / signals[k] : kNaN;
  }
  return s;
}

// The scores of a bit's posterior P(bit = 1) = p1 against the truth's bit.
void CountBit(double p1, bool truth, double margin, TruthOutcome& o, std::size_t k) {
  o.entropy += BinaryEntropy(p1);
  o.decided[k] = std::abs(2.0 * p1 - 1.0);
  if (std::abs(p1 - 0.5) > margin) {
    ++o.identified;
    if ((p1 > 0.5) != truth) ++o.wrong;
  }
}

// The population reweighted (ScoreCandidates).
class Scorer {
 public:
  Scorer(const Population& population,
         const std::vector<CandidateProfiles>& candidates,
         const DesignOptions& options)
      : pop_(population), candidates_(candidates), options_(options) {
    const std::size_t n = pop_.size();
    log_weight_.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      log_weight_[i] = pop_.weights[i] > 0.0 ? std::log(pop_.weights[i]) : kMinusInf;
    }
    truth_ = DrawTruths(pop_.weights, options_.truths, options_.seed);
    // Each truth's one-bit flips, where the population holds them (an exhaustive one does): what
    // "the response is below the noise" is measured by.
    const auto d = static_cast<std::size_t>(pop_.dimension);
    std::map<std::vector<std::uint8_t>, std::size_t> index;
    for (std::size_t i = 0; i < n; ++i) {
      index.emplace(
          std::vector<std::uint8_t>(pop_.bits.begin() + static_cast<std::ptrdiff_t>(i * d),
                                    pop_.bits.begin() + static_cast<std::ptrdiff_t>(i * d + d)),
          i);
    }
    flip_.resize(truth_.size());
    for (std::size_t j = 0; j < truth_.size(); ++j) {
      std::vector<std::uint8_t> bits(
          pop_.bits.begin() + static_cast<std::ptrdiff_t>(truth_[j] * d),
          pop_.bits.begin() + static_cast<std::ptrdiff_t>(truth_[j] * d + d));
      flip_[j].assign(d, -1);
      for (std::size_t k = 0; k < d; ++k) {
        bits[k] ^= 1U;
        const auto it = index.find(bits);
        if (it != index.end()) flip_[j][k] = static_cast<std::ptrdiff_t>(it->second);
        bits[k] ^= 1U;
      }
    }
  }

  std::size_t Width(std::size_t) const { return pop_.size(); }

  // log p(y_jc | particle i) up to a constant, for every particle.
  void LogLikelihood(int c, int j, std::span<double> out) const {
    const CandidateProfiles& profiles = candidates_[static_cast<std::size_t>(c)];
    const auto m = static_cast<std::size_t>(profiles.points);
    const std::vector<double> y =
        TruthData(profiles, truth_[static_cast<std::size_t>(j)], c, j, options_);
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

  // The posterior of truth j given the log-likelihood `ll` of its data; `extra` (-1: none) the
  // candidate whose flips' signal is measured.
  TruthOutcome Outcome(int j, std::span<const double> ll, int extra) const {
    const std::size_t n = pop_.size();
    const auto d = static_cast<std::size_t>(pop_.dimension);
    double top = kMinusInf;
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
    const std::size_t row = truth_[static_cast<std::size_t>(j)];
    const std::uint8_t* truth = pop_.bits.data() + row * d;
    for (std::size_t k = 0; k < d; ++k) {
      CountBit(p[k] / total, truth[k] != 0, options_.identified_margin, o, k);
    }
    if (extra >= 0) {
      const CandidateProfiles& profiles = candidates_[static_cast<std::size_t>(extra)];
      const double scale = 1.0 / (2.0 * options_.noise_sigma * options_.noise_sigma);
      o.signal.assign(d, kNaN);
      for (std::size_t k = 0; k < d; ++k) {
        const std::ptrdiff_t f = flip_[static_cast<std::size_t>(j)][k];
        if (f >= 0) {
          o.signal[k] = SquaredDistance(profiles, row, static_cast<std::size_t>(f)) * scale;
        }
      }
    }
    return o;
  }

  int dimension() const { return pop_.dimension; }

 private:
  const Population& pop_;
  const std::vector<CandidateProfiles>& candidates_;
  const DesignOptions& options_;
  std::vector<double> log_weight_;
  std::vector<std::size_t> truth_;
  std::vector<std::vector<std::ptrdiff_t>> flip_;  // per truth, per bit: its flip's index, or -1
};

// The truths' neighbourhoods (ScoreNeighbourhoods).
class LocalScorer {
 public:
  LocalScorer(const LocalPopulation& population,
              const std::vector<CandidateProfiles>& candidates,
              const DesignOptions& options)
      : pop_(population), candidates_(candidates), options_(options) {}

  std::size_t Width(std::size_t j) const { return pop_.truths[j].rows.size(); }

  // log p(y_jc | configuration) up to a constant, for each row of truth j's neighbourhood.
  void LogLikelihood(int c, int j, std::span<double> out) const {
    const CandidateProfiles& profiles = candidates_[static_cast<std::size_t>(c)];
    const auto m = static_cast<std::size_t>(profiles.points);
    const Neighbourhood& nb = pop_.truths[static_cast<std::size_t>(j)];
    const std::vector<double> y =
        TruthData(profiles, static_cast<std::size_t>(nb.rows.front()), c, j, options_);
    const double scale = 1.0 / (2.0 * options_.noise_sigma * options_.noise_sigma);
    for (std::size_t p = 0; p < nb.rows.size(); ++p) {
      const double* yi = profiles.values.data() + static_cast<std::size_t>(nb.rows[p]) * m;
      double sse = 0.0;
      for (std::size_t k = 0; k < m; ++k) {
        const double r = y[k] - yi[k];
        sse += r * r;
      }
      out[p] = -sse * scale;
    }
  }

  TruthOutcome Outcome(int j, std::span<const double> ll, int extra) const {
    const Neighbourhood& nb = pop_.truths[static_cast<std::size_t>(j)];
    std::vector<double> lw(nb.rows.size());
    double top = kMinusInf;
    for (std::size_t p = 0; p < lw.size(); ++p) {
      lw[p] = pop_.log_weight[static_cast<std::size_t>(nb.rows[p])] + ll[p];
      top = std::max(top, lw[p]);
    }
    const std::vector<double> correct = ProbabilityOfTruth(nb, lw);
    TruthOutcome o;
    double total = 0.0, squares = 0.0;
    for (double a : lw) {
      if (top == kMinusInf) break;
      const double w = std::exp(a - top);
      total += w;
      squares += w * w;
    }
    o.effective = squares > 0.0 ? total * total / squares : 0.0;
    const auto d = static_cast<std::size_t>(pop_.dimension);
    o.decided.resize(d);
    const auto row = static_cast<std::size_t>(nb.rows.front());
    const std::uint8_t* truth = pop_.bits.data() + row * d;
    for (std::size_t k = 0; k < d; ++k) {
      const double c = correct[static_cast<std::size_t>(pop_.free_of_bit[k])];
      CountBit(truth[k] ? c : 1.0 - c, truth[k] != 0, options_.identified_margin, o, k);
    }
    if (extra >= 0) {
      const CandidateProfiles& profiles = candidates_[static_cast<std::size_t>(extra)];
      const double scale = 1.0 / (2.0 * options_.noise_sigma * options_.noise_sigma);
      o.signal.assign(d, kNaN);
      for (std::size_t k = 0; k < d; ++k) {
        const int p = nb.single[static_cast<std::size_t>(pop_.free_of_bit[k])];
        if (p < 0) continue;
        o.signal[k] =
            SquaredDistance(
                profiles, row, static_cast<std::size_t>(nb.rows[static_cast<std::size_t>(p)])) *
            scale;
      }
    }
    return o;
  }

  int dimension() const { return pop_.dimension; }

 private:
  const LocalPopulation& pop_;
  const std::vector<CandidateProfiles>& candidates_;
  const DesignOptions& options_;
};

// The score of experiments `chosen` plus `extra` (-1: none), given base[j] = the summed
// log-likelihood of `chosen` for truth j (empty: none chosen).
template <class S>
Score Evaluate(const S& scorer,
               std::size_t truths,
               const std::vector<std::vector<double>>& base,
               int extra,
               ThreadPool& pool,
               double prior_entropy) {
  std::vector<TruthOutcome> outcomes(truths);
  pool.ParallelFor(truths, 4, [&](std::size_t begin, std::size_t end) {
    std::vector<double> ll;
    for (std::size_t j = begin; j < end; ++j) {
      ll.assign(scorer.Width(j), 0.0);
      if (extra >= 0) scorer.LogLikelihood(extra, static_cast<int>(j), ll);
      if (!base.empty()) {
        for (std::size_t i = 0; i < ll.size(); ++i) ll[i] += base[j][i];
      }
      outcomes[j] = scorer.Outcome(static_cast<int>(j), ll, extra);
    }
  });
  return Aggregate(outcomes, scorer.dimension(), prior_entropy);
}

// Each candidate alone, then greedy: the best candidate, then the one that adds most to it, ...
// (each step keeps the chosen experiments' summed log-likelihood per truth).
template <class S>
void ScoreAndSelect(const S& scorer,
                    std::size_t truths,
                    int count,
                    int select,
                    ThreadPool& pool,
                    DesignResult& result) {
  const std::vector<std::vector<double>> none;
  for (int c = 0; c < count; ++c) {
    result.scores.push_back(Evaluate(scorer, truths, none, c, pool, result.prior_entropy));
  }
  std::vector<std::vector<double>> base;
  std::vector<bool> taken(static_cast<std::size_t>(count), false);
  for (int step = 0; step < std::min(select, count); ++step) {
    int best = -1;
    Score best_score;
    for (int c = 0; c < count; ++c) {
      if (taken[static_cast<std::size_t>(c)]) continue;
      Score s = step == 0 ? result.scores[static_cast<std::size_t>(c)]
                          : Evaluate(scorer, truths, base, c, pool, result.prior_entropy);
      // Ties go to the earlier candidate: the order of the grid decides, not the threads.
      if (best < 0 || s.information_gain > best_score.information_gain) {
        best = c;
        best_score = std::move(s);
      }
    }
    taken[static_cast<std::size_t>(best)] = true;
    result.selected.push_back(best);
    result.cumulative.push_back(best_score);
    if (base.empty()) {
      base.resize(truths);
      for (std::size_t j = 0; j < truths; ++j) base[j].assign(scorer.Width(j), 0.0);
    }
    pool.ParallelFor(truths, 4, [&](std::size_t begin, std::size_t end) {
      std::vector<double> ll;
      for (std::size_t j = begin; j < end; ++j) {
        ll.assign(scorer.Width(j), 0.0);
        scorer.LogLikelihood(best, static_cast<int>(j), ll);
        for (std::size_t i = 0; i < ll.size(); ++i) base[j][i] += ll[i];
      }
    });
  }
}

void CheckOptions(const DesignOptions& options);

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
  if (options.truths < 2) fail("truths must be >= 2");
  CheckOptions(options);
}

void CheckOptions(const DesignOptions& options) {
  auto fail = [](const std::string& why) { throw std::invalid_argument("design: " + why); };
  if (!(options.noise_sigma > 0.0) || !std::isfinite(options.noise_sigma)) {
    fail("noise_sigma must be finite and > 0");
  }
  if (options.select < 1) fail("select must be >= 1");
  if (!(options.identified_margin >= 0.0 && options.identified_margin < 0.5)) {
    fail("identified_margin must be in [0, 0.5)");
  }
}

}  // namespace

std::vector<double> ProbabilityOfTruth(const Neighbourhood& nb, std::span<const double> lw) {
  if (lw.size() != nb.rows.size() || lw.empty()) {
    throw std::invalid_argument("design: one log weight per neighbourhood row");
  }
  auto at = [&](int position) {
    return position < 0 ? kMinusInf : lw[static_cast<std::size_t>(position)];
  };
  // P(free parameter = the truth's value): the two-state posterior against its flip, then the
  // four-state one of each pair it is in; the least of them (the most confusable alternative).
  const std::size_t free = nb.single.size();
  std::vector<double> correct(free, 1.0);
  for (std::size_t f = 0; f < free; ++f) {
    const double a0 = lw[0], a1 = at(nb.single[f]);
    const double m = std::max(a0, a1);
    if (m == kMinusInf) continue;
    const double w0 = std::exp(a0 - m), w1 = std::exp(a1 - m);
    correct[f] = std::min(correct[f], w0 / (w0 + w1));
  }
  for (const Neighbourhood::Swap& s : nb.swaps) {
    const auto f = static_cast<std::size_t>(s.first), g = static_cast<std::size_t>(s.second);
    const double a0 = lw[0], af = at(nb.single[f]), ag = at(nb.single[g]), afg = at(s.position);
    const double m = std::max({a0, af, ag, afg});
    if (m == kMinusInf) continue;
    const double w0 = std::exp(a0 - m), wf = std::exp(af - m), wg = std::exp(ag - m),
                 wfg = std::exp(afg - m);
    const double total = w0 + wf + wg + wfg;
    correct[f] = std::min(correct[f], (w0 + wg) / total);
    correct[g] = std::min(correct[g], (w0 + wf) / total);
  }
  for (const Neighbourhood::Group& group : nb.groups) {
    const double a0 = lw[0], a1 = at(group.position);
    const double m = std::max(a0, a1);
    if (m == kMinusInf) continue;
    const double w0 = std::exp(a0 - m), w1 = std::exp(a1 - m);
    for (int f : group.flipped) {
      correct[static_cast<std::size_t>(f)] =
          std::min(correct[static_cast<std::size_t>(f)], w0 / (w0 + w1));
    }
  }
  return correct;
}

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

std::vector<std::size_t> DrawTruths(std::span<const double> weights,
                                    int truths,
                                    std::uint64_t seed) {
  const std::size_t n = weights.size();
  std::vector<double> cdf(n);
  double total = 0.0;
  for (std::size_t i = 0; i < n; ++i) cdf[i] = total += weights[i];
  std::vector<std::size_t> out;
  for (int j = 0; j < truths; ++j) {
    RandomStream rng(seed, kTruthStream, static_cast<std::uint64_t>(j));
    const double u = rng.Uniform() * total;
    const auto it = std::upper_bound(cdf.begin(), cdf.end(), u);
    out.push_back(std::min<std::size_t>(static_cast<std::size_t>(it - cdf.begin()), n - 1));
  }
  return out;
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
  ScoreAndSelect(scorer,
                 static_cast<std::size_t>(options.truths),
                 static_cast<int>(candidates.size()),
                 options.select,
                 pool,
                 result);
  return result;
}

DesignResult ScoreNeighbourhoods(const LocalPopulation& population,
                                 const std::vector<CandidateProfiles>& candidates,
                                 const DesignOptions& options) {
  auto fail = [](const std::string& why) { throw std::invalid_argument("design: " + why); };
  const std::size_t rows = population.rows();
  const auto d = static_cast<std::size_t>(population.dimension);
  if (d == 0 || rows == 0 || population.truths.size() < 2) fail("empty neighbourhoods");
  if (population.bits.size() != rows * d || population.free_of_bit.size() != d) {
    fail("neighbourhood bits must be rows() x dimension");
  }
  const int free =
      *std::max_element(population.free_of_bit.begin(), population.free_of_bit.end()) + 1;
  for (const Neighbourhood& nb : population.truths) {
    if (nb.rows.empty() || nb.single.size() != static_cast<std::size_t>(free)) {
      fail("each neighbourhood needs its truth and one entry per free parameter");
    }
    for (int r : nb.rows) {
      if (r < 0 || static_cast<std::size_t>(r) >= rows) fail("neighbourhood row out of range");
    }
    auto position = [&](int p) { return p < static_cast<int>(nb.rows.size()); };
    for (int p : nb.single) {
      if (!position(p)) fail("neighbourhood position out of range");
    }
    for (const Neighbourhood::Group& g : nb.groups) {
      if (!position(g.position)) fail("neighbourhood group out of range");
      for (int f : g.flipped) {
        if (f < 0 || f >= free) fail("neighbourhood group out of range");
      }
    }
    for (const Neighbourhood::Swap& s : nb.swaps) {
      if (s.first < 0 || s.first >= free || s.second < 0 || s.second >= free || s.position < 0 ||
          !position(s.position)) {
        fail("neighbourhood swap out of range");
      }
    }
  }
  if (candidates.empty()) fail("no candidates");
  for (const CandidateProfiles& c : candidates) {
    if (c.points < 1 || c.values.size() != rows * static_cast<std::size_t>(c.points)) {
      fail("candidate profiles must be rows() x points");
    }
  }
  CheckOptions(options);

  ThreadPool pool(options.threads);
  const LocalScorer scorer(population, candidates, options);
  const std::size_t truths = population.truths.size();
  DesignResult result;
  // Before any new data: the neighbourhoods' own marginals, from which the gains count.
  const Score before = Evaluate(scorer, truths, {}, -1, pool, 0.0);
  result.prior_entropy = -before.information_gain;
  result.prior_identified = before.identified;
  ScoreAndSelect(scorer, truths, static_cast<int>(candidates.size()), options.select, pool, result);
  return result;
}

}  // namespace combabc::design
