// Coverage of the Monte-Carlo standard errors over seeds (docs/benchmarks.md, "Monte-Carlo error
// coverage"): on two problems with an exact ABC posterior, many seeds of the sampler, and for
// every reported quantity (P(bit = 1), configuration masses, a real's mean and sd) how often the
// nominal 95 % interval estimate ± 1.96 SE holds the exact value, and the seed-to-seed spread
// over the typical SE. Two standard errors: the ESS-based one (sqrt(p (1 - p) / ESS),
// sd / sqrt(ESS), sd / sqrt(2 ESS)) and the delta method's (samplers/monte_carlo_error.hpp).
// COMBABC_BENCH_SEEDS seeds (default 20), N = 1000 particles per wave.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "combabc/samplers/combinatorial_smc.hpp"
#include "combabc/samplers/enumeration.hpp"
#include "combabc/samplers/monte_carlo_error.hpp"
#include "samplers/linear_gaussian.hpp"
#include "samplers/mixture_model.hpp"
#include "samplers/toy_models.hpp"

namespace {

using namespace combabc;

int Seeds() {
  const char* s = std::getenv("COMBABC_BENCH_SEEDS");
  return s != nullptr ? std::max(2, std::atoi(s)) : 20;
}

// One quantity over seeds: estimates and the two standard errors.
struct Tally {
  double exact = 0.0;
  std::vector<double> estimate, se_ess, se_delta;
};
// kind -> quantity name -> tally
using Tallies = std::map<std::string, std::map<std::string, Tally>>;

void Add(Tallies& t,
         const std::string& kind,
         const std::string& name,
         double exact,
         double estimate,
         double se_ess,
         double se_delta) {
  Tally& x = t[kind][name];
  x.exact = exact;
  x.estimate.push_back(estimate);
  x.se_ess.push_back(se_ess);
  x.se_delta.push_back(se_delta);
}

// Per kind: covered / intervals for both SEs, and the median over quantities of the spread of
// the estimates around the exact value (RMS) over the RMS standard error.
void Report(const char* problem,
            const char* schedule,
            const Tallies& tallies,
            benchmark::State& state) {
  for (const auto& [kind, quantities] : tallies) {
    int n = 0, cover_ess = 0, cover_delta = 0;
    std::vector<double> ratio_ess, ratio_delta;
    for (const auto& [name, x] : quantities) {
      double err2 = 0.0, ess2 = 0.0, delta2 = 0.0;
      for (std::size_t s = 0; s < x.estimate.size(); ++s) {
        const double e = x.estimate[s] - x.exact;
        ++n;
        cover_ess += std::abs(e) <= 1.96 * x.se_ess[s];
        cover_delta += std::abs(e) <= 1.96 * x.se_delta[s];
        err2 += e * e;
        ess2 += x.se_ess[s] * x.se_ess[s];
        delta2 += x.se_delta[s] * x.se_delta[s];
      }
      if (ess2 > 0.0) ratio_ess.push_back(std::sqrt(err2 / ess2));
      if (delta2 > 0.0) ratio_delta.push_back(std::sqrt(err2 / delta2));
    }
    const auto median = [](std::vector<double> v) {
      if (v.empty()) return std::nan("");
      std::sort(v.begin(), v.end());
      return v[v.size() / 2];
    };
    std::printf(
        "%-7s %-9s %-6s intervals %4d  ESS-SE covers %5.1f %% (spread/SE %.2f)  "
        "delta-SE covers %5.1f %% (spread/SE %.2f)\n",
        problem,
        schedule,
        kind.c_str(),
        n,
        100.0 * cover_ess / n,
        median(ratio_ess),
        100.0 * cover_delta / n,
        median(ratio_delta));
    state.counters[kind + "_cover_ess"] = static_cast<double>(cover_ess) / n;
    state.counters[kind + "_cover_delta"] = static_cast<double>(cover_delta) / n;
  }
}

ThresholdSchedule Schedule(bool list, std::vector<double> values) {
  ThresholdSchedule s;
  if (list) {
    s.kind = ThresholdKind::kList;
    s.values = std::move(values);
  } else {
    s.kind = ThresholdKind::kQuantile;
    s.target = values.back();
  }
  return s;
}

double Naive(double p, double ess) { return std::sqrt(std::max(0.0, p * (1.0 - p)) / ess); }

// Configuration masses: the particles' weight on each configuration (bit k = bit k of c).
std::vector<double> Masses(const WaveRecord& w, std::size_t d) {
  std::vector<double> m(std::size_t{1} << d, 0.0);
  for (const Particle& p : w.particles) {
    std::size_t c = 0;
    for (std::size_t k = 0; k < d; ++k) c |= static_cast<std::size_t>(p.theta.bits[k] != 0) << k;
    m[c] += p.weight;
  }
  return m;
}
WeightedMoment MassOf(const WaveRecord& w, std::size_t c) {
  std::vector<double> weights, x;
  for (const Particle& p : w.particles) {
    std::size_t code = 0;
    for (std::size_t k = 0; k < p.theta.bits.size(); ++k) {
      code |= static_cast<std::size_t>(p.theta.bits[k] != 0) << k;
    }
    weights.push_back(p.weight);
    x.push_back(code == c ? 1.0 : 0.0);
  }
  return WeightedMean(weights, x);
}

// The mixed toy of continuous_test.cpp: bits b1..b3 (weights 1, -0.5, 2) plus theta ~ U(-2, 2);
// y = 1.7, sigma = 0.3, final eps = 0.25. Arg: 1 list thresholds {2, 1, 0.5, 0.25}, 0 the
// default quantile schedule down to 0.25.
void BM_CoverageMixed(benchmark::State& state) {
  const bool list = state.range(0) == 1;
  ContinuousPrior prior;
  prior.kind = PriorKind::kUniform;
  prior.low = -2.0;
  prior.high = 2.0;
  const std::vector<double> w = {1.0, -0.5, 2.0};
  const std::vector<double> bit_prior = {0.5, 0.3, 0.6};
  BinarySpaceOptions so;
  so.dimension = 3;
  so.prior_one = bit_prior;
  const ParameterSpace space(BinarySpace(so), {{"theta", prior}});
  const testing::LinearGaussianSimulator sim(w, 0.3);
  const testing::AbsoluteDistance dist(1.7);
  const auto exact = testing::ExactPosterior(w, bit_prior, prior, 0.3, 1.7, 0.25, -2.0, 2.0);
  for (auto _ : state) {
    Tallies t;
    double waves = 0.0;
    for (int seed = 1; seed <= Seeds(); ++seed) {
      SmcOptions o;
      o.num_waves = list ? 4 : 30;
      o.accepted_per_wave = 1000;
      o.seed = static_cast<std::uint64_t>(seed);
      o.threads = 2;
      o.thresholds = {Schedule(list, {2.0, 1.0, 0.5, 0.25})};
      const auto h = RunCombinatorialSmc({&space, &sim, &dist}, o);
      if (h.summary.termination != Termination::kTargetReached) {
        state.SkipWithError("a run did not reach its target");
        return;
      }
      waves += static_cast<double>(h.waves.size());
      const WaveRecord& last = h.waves.back();
      const WaveErrors e = WaveMonteCarloErrors(last);
      for (std::size_t k = 0; k < 3; ++k) {
        Add(t,
            "bits",
            "b" + std::to_string(k),
            exact.bit_mean[k],
            e.bits[k].value,
            Naive(e.bits[k].value, last.ess),
            e.bits[k].se);
      }
      const std::vector<double> m = Masses(last, 3);
      for (std::size_t c = 0; c < m.size(); ++c) {
        if (exact.configuration_mass[c] < 0.01) continue;
        Add(t,
            "masses",
            std::to_string(c),
            exact.configuration_mass[c],
            m[c],
            Naive(m[c], last.ess),
            MassOf(last, c).se);
      }
      const double sd = e.real_sds[0].value;
      Add(t,
          "mean",
          "theta",
          exact.mean,
          e.real_means[0].value,
          sd / std::sqrt(last.ess),
          e.real_means[0].se);
      Add(t,
          "sd",
          "theta",
          std::sqrt(exact.var),
          sd,
          sd / std::sqrt(2.0 * last.ess),
          e.real_sds[0].se);
    }
    Report("mixed", list ? "list" : "quantile", t, state);
    state.counters["waves"] = waves / Seeds();
  }
}
BENCHMARK(BM_CoverageMixed)->Arg(1)->Arg(0)->Iterations(1)->Unit(benchmark::kSecond);

// The binary toy of exactness_test.cpp: d = 12, the deterministic identity simulator, final
// eps = 3 (exact by enumeration). Arg: 1 list thresholds {12, 8, 6, 4.5, 3}, 0 the default
// quantile schedule down to 3.
void BM_CoverageBinary(benchmark::State& state) {
  const bool list = state.range(0) == 1;
  constexpr int kBits = 12;
  BinarySpaceOptions so;
  so.dimension = kBits;
  so.prior_one = {0.5, 0.3, 0.6, 0.5, 0.4, 0.7, 0.5, 0.2, 0.5, 0.6, 0.5, 0.35};
  const ParameterSpace space{BinarySpace(so)};
  const testing::IdentitySimulator sim(kBits);
  const testing::WeightedL1Distance dist({1, 0, 1, 1, 0, 0, 1, 0, 1, 1, 0, 0},
                                         {4, 2, 2, 2, 1.5, 1.5, 1, 1, 1, 0.5, 0.5, 0},
                                         1,
                                         2,
                                         1.0);
  EnumerationOptions eo;
  eo.thresholds = {3.0};
  eo.threads = 2;
  const EnumerationResult exact = Enumerate({&space, &sim, &dist}, eo);
  for (auto _ : state) {
    Tallies t;
    double waves = 0.0;
    for (int seed = 1; seed <= Seeds(); ++seed) {
      SmcOptions o;
      o.num_waves = list ? 5 : 30;
      o.accepted_per_wave = 1000;
      o.seed = static_cast<std::uint64_t>(seed);
      o.threads = 2;
      o.thresholds = {Schedule(list, {12, 8, 6, 4.5, 3})};
      const auto h = RunCombinatorialSmc({&space, &sim, &dist}, o);
      if (h.summary.termination != Termination::kTargetReached) {
        state.SkipWithError("a run did not reach its target");
        return;
      }
      waves += static_cast<double>(h.waves.size());
      const WaveRecord& last = h.waves.back();
      const WaveErrors e = WaveMonteCarloErrors(last);
      for (std::size_t k = 0; k < kBits; ++k) {
        // A bit whose exact posterior is 0 or 1 has no Monte-Carlo error.
        if (exact.marginals[k] < 1e-9 || exact.marginals[k] > 1.0 - 1e-9) continue;
        Add(t,
            "bits",
            "b" + std::to_string(k),
            exact.marginals[k],
            e.bits[k].value,
            Naive(e.bits[k].value, last.ess),
            e.bits[k].se);
      }
      const std::vector<double> m = Masses(last, kBits);
      for (const Particle& top : exact.top) {
        const auto c = static_cast<std::size_t>(top.index);
        Add(t,
            "masses",
            std::to_string(c),
            top.weight,
            m[c],
            Naive(m[c], last.ess),
            MassOf(last, c).se);
      }
    }
    Report("binary", list ? "list" : "quantile", t, state);
    state.counters["waves"] = waves / Seeds();
  }
}
BENCHMARK(BM_CoverageBinary)->Arg(1)->Arg(0)->Iterations(1)->Unit(benchmark::kSecond);

}  // namespace

namespace {

// max_k |y_k - y*_k|: with independent priors and noise the ABC posterior is a product over the
// dimensions, each a one-dimensional quadrature (linear_gaussian.hpp).
class MaxDistance : public Distance {
 public:
  explicit MaxDistance(std::vector<double> observed) : observed_(std::move(observed)) {}
  std::vector<DistanceComponent> components() const override {
    return {{"max", ComponentKind::kThreshold, 1.0}};
  }
  void Evaluate(std::span<const double> y, std::span<double> out) const override {
    double d = 0.0;
    for (std::size_t k = 0; k < observed_.size(); ++k) {
      d = std::max(d, std::abs(y[k] - observed_[k]));
    }
    out[0] = d;
  }

 private:
  std::vector<double> observed_;
};

// y_k = theta_k + sigma e_k.
class ShiftSimulator : public Simulator {
 public:
  ShiftSimulator(int d, double sigma) : d_(d), sigma_(sigma) {}
  int output_size() const override { return d_; }
  void Simulate(const ParameterView& theta,
                RandomStream& rng,
                std::span<double> out) const override {
    for (int k = 0; k < d_; ++k) out[k] = theta.reals[k] + sigma_ * rng.Normal();
  }

 private:
  int d_;
  double sigma_;
};

// Ten informative reals theta_k ~ N(0, 2^2), y_k = theta_k + N(0, 0.5^2), y* = 1.
// range(0): 1 list thresholds {4, 2.5, 1.8, 1.3, 1}, 2 one jump {4, 2} (uneven weights: the
// kernel fitted at 4 is far wider than the posterior at 2), 0 the default quantile schedule down
// to 1;
// range(1): the continuous kernel.
void BM_CoverageTenReals(benchmark::State& state) {
  const bool list = state.range(0) >= 1;
  const bool jump = state.range(0) == 2;
  constexpr int kReals = 10;
  ContinuousPrior prior;
  prior.kind = PriorKind::kNormal;
  prior.mean = 0.0;
  prior.sd = 2.0;
  std::vector<ContinuousParameter> reals;
  reals.reserve(kReals);
  for (int k = 0; k < kReals; ++k) reals.push_back({"t" + std::to_string(k), prior});
  const ParameterSpace space(BinarySpace::Independent(0), reals);
  const ShiftSimulator sim(kReals, 0.5);
  const MaxDistance dist(std::vector<double>(kReals, 1.0));
  const std::vector<double> eps =
      jump ? std::vector<double>{4.0, 2.0} : std::vector<double>{4.0, 2.5, 1.8, 1.3, 1.0};
  const auto exact = testing::ExactPosterior({}, {}, prior, 0.5, 1.0, eps.back(), -12.0, 12.0);
  for (auto _ : state) {
    Tallies t;
    double waves = 0.0, ess = 0.0, sims = 0.0;
    for (int seed = 1; seed <= Seeds(); ++seed) {
      SmcOptions o;
      o.num_waves = list ? static_cast<int>(eps.size()) : 40;
      o.accepted_per_wave = 500;
      o.seed = static_cast<std::uint64_t>(seed);
      o.threads = 2;
      o.proposal.continuous = static_cast<ContinuousKernelKind>(state.range(1));
      o.thresholds = {Schedule(list, eps)};
      const auto h = RunCombinatorialSmc({&space, &sim, &dist}, o);
      if (h.summary.termination != Termination::kTargetReached) {
        state.SkipWithError(h.summary.message.c_str());
        return;
      }
      waves += static_cast<double>(h.waves.size());
      const WaveRecord& last = h.waves.back();
      ess += last.ess;
      sims += static_cast<double>(h.summary.simulations);
      const WaveErrors e = WaveMonteCarloErrors(last);
      for (int k = 0; k < kReals; ++k) {
        const double sd = e.real_sds[k].value;
        Add(t,
            "mean",
            "t" + std::to_string(k),
            exact.mean,
            e.real_means[k].value,
            sd / std::sqrt(last.ess),
            e.real_means[k].se);
        Add(t,
            "sd",
            "t" + std::to_string(k),
            std::sqrt(exact.var),
            sd,
            sd / std::sqrt(2.0 * last.ess),
            e.real_sds[k].se);
      }
    }
    Report("10reals", jump ? "list-jump" : list ? "list" : "quantile", t, state);
    state.counters["waves"] = waves / Seeds();
    state.counters["ess"] = ess / Seeds();
    state.counters["simulations"] = sims / Seeds();
  }
}
// The normal kernel only: a run takes about 1.5 M simulations (minutes for 20 seeds).
BENCHMARK(BM_CoverageTenReals)->Args({1, 0})->Args({2, 0})->Iterations(1)->Unit(benchmark::kSecond);

}  // namespace

namespace {

// The mixture toy (mixture_model.hpp). range(0): 1 list thresholds {2, 0.5, 0.1, 0.025}, 0 the
// default quantile schedule down to 0.025; range(1): the continuous kernel.
void BM_CoverageMixture(benchmark::State& state) {
  const bool list = state.range(0) == 1;
  const ParameterSpace space(BinarySpace::Independent(0), {{"theta", testing::MixturePrior()}});
  const testing::MixtureSimulator sim;
  const testing::AbsoluteDistance dist(0.0);
  const std::vector<double> eps = {2.0, 0.5, 0.1, 0.025};
  const testing::MixtureMoments exact = testing::ExactMixtureMoments(eps.back());
  for (auto _ : state) {
    Tallies t;
    double waves = 0.0, ess = 0.0, sims = 0.0;
    for (int seed = 1; seed <= Seeds(); ++seed) {
      SmcOptions o;
      o.num_waves = list ? static_cast<int>(eps.size()) : 40;
      o.accepted_per_wave = 1000;
      o.seed = static_cast<std::uint64_t>(seed);
      o.threads = 2;
      o.proposal.continuous = static_cast<ContinuousKernelKind>(state.range(1));
      o.thresholds = {Schedule(list, eps)};
      const auto h = RunCombinatorialSmc({&space, &sim, &dist}, o);
      if (h.summary.termination != Termination::kTargetReached) {
        state.SkipWithError(h.summary.message.c_str());
        return;
      }
      waves += static_cast<double>(h.waves.size());
      const WaveRecord& last = h.waves.back();
      ess += last.ess;
      sims += static_cast<double>(h.summary.simulations);
      const WaveErrors e = WaveMonteCarloErrors(last);
      const double sd = e.real_sds[0].value;
      Add(t,
          "mean",
          "theta",
          exact.mean,
          e.real_means[0].value,
          sd / std::sqrt(last.ess),
          e.real_means[0].se);
      Add(t, "sd", "theta", exact.sd, sd, sd / std::sqrt(2.0 * last.ess), e.real_sds[0].se);
    }
    Report("mixture", list ? "list" : "quantile", t, state);
    state.counters["waves"] = waves / Seeds();
    state.counters["ess"] = ess / Seeds();
    state.counters["simulations"] = sims / Seeds();
  }
}
BENCHMARK(BM_CoverageMixture)
    ->Args({1, 0})
    ->Args({0, 0})
    ->Args({1, 1})
    ->Args({0, 1})
    ->Iterations(1)
    ->Unit(benchmark::kSecond);

}  // namespace
