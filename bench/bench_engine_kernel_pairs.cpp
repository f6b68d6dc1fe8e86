// Whole runs per kernel pair (issue 23): simulations and CPU seconds per unit of ESS, and the
// errors against the exact ABC posterior, on the minor-modes problem
// (tests/samplers/minor_modes.hpp, 8 bits and one real) and on the Sisson/Beaumont mixture toy
// (theta ~ U(-10, 10), x ~ 0.5 N(theta, 1) + 0.5 N(theta, 1/100), x_obs = 0; continuous only). One
// thread, so that CPU time is the run's own; each repetition runs the next seed (run with
// --benchmark_repetitions=R and read the medians). docs/benchmarks.md records the numbers.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>
#include <ctime>
#include <map>
#include <string>
#include <vector>

#include "combabc/samplers/combinatorial_smc.hpp"
#include "samplers/minor_modes.hpp"

namespace {

using namespace combabc;
namespace mm = combabc::testing::minor_modes;

// Arg 0: the pair (0 independent x normal, 1 independent x olcm, 2 logistic x normal, 3 logistic
// x olcm, 4 ancestor).
struct PairKinds {
  BinaryKernelKind binary;
  ContinuousKernelKind continuous;
};
PairKinds PairOf(std::int64_t arg) {
  switch (arg) {
    case 1:
      return {BinaryKernelKind::kIndependent, ContinuousKernelKind::kOlcm};
    case 2:
      return {BinaryKernelKind::kLogistic, ContinuousKernelKind::kNormal};
    case 3:
      return {BinaryKernelKind::kLogistic, ContinuousKernelKind::kOlcm};
    case 4:
      return {BinaryKernelKind::kAncestor, ContinuousKernelKind::kNormal};
    default:
      return {BinaryKernelKind::kIndependent, ContinuousKernelKind::kNormal};
  }
}

// The next seed of a benchmark (one per repetition), by name.
std::uint64_t NextSeed(const std::string& name) {
  static std::map<std::string, std::uint64_t> seeds;
  return 1000 + seeds[name]++;
}

double ProcessSeconds() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

struct Moments {
  double mean = 0.0, sd = 0.0;
};
Moments RealMoments(const WaveRecord& wave) {
  Moments m;
  for (const auto& p : wave.particles) m.mean += p.weight * p.theta.reals[0];
  double var = 0.0;
  for (const auto& p : wave.particles) {
    var += p.weight * (p.theta.reals[0] - m.mean) * (p.theta.reals[0] - m.mean);
  }
  m.sd = std::sqrt(var);
  return m;
}

void Report(benchmark::State& state, const RunHistory& h, double cpu) {
  const auto& last = h.waves.back();
  const auto sims = static_cast<double>(h.summary.simulations);
  state.counters["simulations"] = sims;
  state.counters["ess"] = last.ess;
  state.counters["sims_per_ess"] = sims / last.ess;
  state.counters["cpu_ms_per_ess"] = 1e3 * cpu / last.ess;
}

// Arg 1: the variant of the problem (0 single flips, 1 joint flips).
void BM_MinorModes(benchmark::State& state) {
  const PairKinds pair = PairOf(state.range(0));
  const auto variant = state.range(1) == 1 ? mm::Variant::kJointFlips : mm::Variant::kSingleFlips;
  const ParameterSpace space = mm::Space();
  const mm::Simulator sim(variant);
  const mm::Distance dist;
  const mm::Exact exact = mm::ExactPosterior(variant);
  for (auto _ : state) {
    auto o = mm::Options(
        pair.binary,
        pair.continuous,
        1000,
        NextSeed("minor" + std::to_string(state.range(0)) + "/" + std::to_string(state.range(1))));
    o.threads = 1;
    const double start = ProcessSeconds();
    const RunHistory h = RunCombinatorialSmc({&space, &sim, &dist}, o);
    const double cpu = ProcessSeconds() - start;
    Report(state, h, cpu);
    const auto& last = h.waves.back();
    const Moments m = RealMoments(last);
    double minor_plus = 0.0, minor_minus = 0.0, bit_error = 0.0;
    for (const auto& p : last.particles) {
      const int mode = mm::MinorMode(variant, p.theta.bits);
      if (mode == 1) minor_plus += p.weight;
      if (mode == -1) minor_minus += p.weight;
    }
    for (int k = 0; k < mm::kBits; ++k) {
      bit_error = std::max(bit_error, std::abs(last.marginals_importance[k] - exact.bit_mean[k]));
    }
    state.counters["sd"] = m.sd;
    state.counters["sd_error"] = std::abs(m.sd - exact.sd);
    state.counters["min_minor"] = std::min(minor_plus, minor_minus);
    state.counters["max_bit_error"] = bit_error;
  }
}
BENCHMARK(BM_MinorModes)
    ->ArgsProduct({{0, 1, 2, 3, 4}, {0, 1}})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

// x ~ 0.5 N(theta, 1) + 0.5 N(theta, 0.1^2), from the candidate's stream.
class MixtureSimulator final : public Simulator {
 public:
  int output_size() const override { return 1; }
  void Simulate(const ParameterView& theta,
                RandomStream& rng,
                std::span<double> out) const override {
    const double sd = rng.Uniform() < 0.5 ? 1.0 : 0.1;
    out[0] = theta.reals[0] + sd * rng.Normal();
  }
};

class AbsoluteDistance final : public Distance {
 public:
  std::vector<DistanceComponent> components() const override {
    return {{"abs", ComponentKind::kThreshold, 1.0}};
  }
  void Evaluate(std::span<const double> y, std::span<double> out) const override {
    out[0] = std::abs(y[0]);
  }
};

// The ABC posterior's sd at eps: P(|x| <= eps | theta) on the prior's support, by quadrature.
double MixtureExactSd(double eps) {
  auto phi = [](double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); };
  double z = 0.0, m2 = 0.0;
  constexpr int kSteps = 200000;
  constexpr double kH = 20.0 / kSteps;
  for (int i = 0; i < kSteps; ++i) {
    const double t = -10.0 + (i + 0.5) * kH;
    const double p =
        0.5 * (phi(eps - t) - phi(-eps - t)) + 0.5 * (phi((eps - t) / 0.1) - phi((-eps - t) / 0.1));
    z += p;
    m2 += p * t * t;
  }
  return std::sqrt(m2 / z);  // the mean is 0 by symmetry
}

// Arg 0: 0 normal, 1 olcm, 2 ancestor.
void BM_SissonMixture(benchmark::State& state) {
  ContinuousPrior prior;
  prior.kind = PriorKind::kUniform;
  prior.low = -10.0;
  prior.high = 10.0;
  const ParameterSpace space(BinarySpace::Independent(0), {{"theta", prior}});
  const MixtureSimulator sim;
  const AbsoluteDistance dist;
  const std::vector<double> eps = {2.0, 0.5, 0.025};
  static const double exact_sd = MixtureExactSd(eps.back());
  for (auto _ : state) {
    SmcOptions o;
    o.num_waves = static_cast<int>(eps.size());
    o.accepted_per_wave = 1000;
    o.seed = NextSeed("mixture" + std::to_string(state.range(0)));
    o.threads = 1;
    o.proposal.binary =
        state.range(0) == 2 ? BinaryKernelKind::kAncestor : BinaryKernelKind::kIndependent;
    o.proposal.continuous =
        state.range(0) == 1 ? ContinuousKernelKind::kOlcm : ContinuousKernelKind::kNormal;
    ThresholdSchedule s;
    s.kind = ThresholdKind::kList;
    s.values = eps;
    o.thresholds = {s};
    const double start = ProcessSeconds();
    const RunHistory h = RunCombinatorialSmc({&space, &sim, &dist}, o);
    const double cpu = ProcessSeconds() - start;
    Report(state, h, cpu);
    const Moments m = RealMoments(h.waves.back());
    state.counters["sd"] = m.sd;
    state.counters["sd_error"] = std::abs(m.sd - exact_sd);
  }
}
BENCHMARK(BM_SissonMixture)->DenseRange(0, 2)->Iterations(1)->Unit(benchmark::kMillisecond);

}  // namespace
