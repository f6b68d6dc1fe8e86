#include "history/fake_run.hpp"

#include <algorithm>
#include <cmath>

#include "combabc/rng/random_stream.hpp"

namespace combabc::testing {
namespace {

constexpr double kImpact = 0.45;         // m, shaker position (paper Figure 1)
constexpr double kSectionLength = 0.05;  // m, one clamp section
constexpr double kMeasuredFrom = 0.48;   // m, LDV data range of Figure 1
constexpr double kMeasuredTo = 0.80;

std::vector<double> Positions(int points) {
  std::vector<double> x(static_cast<std::size_t>(points));
  for (int i = 0; i < points; ++i) {
    x[static_cast<std::size_t>(i)] = points > 1 ? 0.9 * i / (points - 1) : 0.0;
  }
  return x;
}

// Sections fixed in the "true" configuration: the paper's clamps 8, 12, 13 (and 26, 30, 31 on the
// other edge, i.e. the same sections).
bool TrulyFixed(int section) { return section == 7 || section == 11 || section == 12; }

int Sections(int dimension) { return dimension % 2 == 0 ? dimension / 2 : dimension; }

double SectionCentre(int section, int sections) {
  return (section + 0.5) * kSectionLength * 18.0 / std::max(sections, 1);
}

// Normalised |w| along the plate for a clamp configuration: a peak at the impact point that widens
// when the clamps around it are free, plus secondary bumps at free clamps further away.
std::vector<double> Curve(const std::vector<std::uint8_t>& bits, const std::vector<double>& x) {
  const int d = static_cast<int>(bits.size());
  const int sections = Sections(d);
  std::vector<double> fixity(static_cast<std::size_t>(sections), 0.0);
  for (int k = 0; k < d; ++k) {
    fixity[static_cast<std::size_t>(k % sections)] += bits[static_cast<std::size_t>(k)] ? 1.0 : 0.0;
  }
  for (double& f : fixity) f /= (d == sections ? 1.0 : 2.0);
  double width = 0.035;
  for (int s = 0; s < sections; ++s) {
    const double dist = std::abs(SectionCentre(s, sections) - kImpact);
    if (dist < 0.1) width += 0.012 * (1.0 - fixity[static_cast<std::size_t>(s)]);
  }
  std::vector<double> y(x.size());
  double peak = 0.0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    double value = std::exp(-std::pow((x[i] - kImpact) / width, 2));
    for (int s = 0; s < sections; ++s) {
      const double centre = SectionCentre(s, sections);
      const double dist = std::abs(centre - kImpact);
      if (dist < 0.08 || dist > 0.3) continue;
      const double amplitude =
          0.3 * (1.0 - fixity[static_cast<std::size_t>(s)]) * std::exp(-dist / 0.1);
      value += amplitude * std::exp(-std::pow((x[i] - centre) / 0.015, 2));
    }
    y[i] = std::abs(value);
    peak = std::max(peak, y[i]);
  }
  for (double& v : y) v /= peak;
  return y;
}

std::vector<std::uint8_t> TrueBits(int dimension) {
  std::vector<std::uint8_t> bits(static_cast<std::size_t>(dimension));
  const int sections = Sections(dimension);
  for (int k = 0; k < dimension; ++k) bits[static_cast<std::size_t>(k)] = TrulyFixed(k % sections);
  return bits;
}

}  // namespace

RunMetadata MakeFakeMetadata(const FakeRunOptions& options) {
  RunMetadata m;
  m.config_text = "# synthetic run for tests\n[smc]\nwaves = " + std::to_string(options.waves) +
                  "\naccepted_per_wave = " + std::to_string(options.per_wave) +
                  "\nseed = " + std::to_string(options.seed) + "\n";
  m.config_path = "tests/fake.toml";
  m.git_hash = "0123456789abcdef";
  m.seed = options.seed;
  m.threads = 2;
  m.estimator = "paper";
  m.dimension = options.dimension;
  for (int k = 0; k < options.dimension; ++k) {
    m.bit_names.push_back("clamp " + std::to_string(k + 1));
  }
  m.distance_components = {{"least squares", ComponentKind::kThreshold, 1.0},
                           {"secondary peak", ComponentKind::kIndicator, 1.0}};
  m.output_positions = Positions(options.points);
  m.position_unit = "m";
  for (int i = 0; i < options.reals; ++i) {
    ContinuousParameter parameter;
    parameter.name = "stiffness_" + std::to_string(i + 1);
    parameter.prior = {PriorKind::kUniform, 1e4, 1e5, 0.0, 1.0};
    m.reals.push_back(parameter);
  }
  m.tempering_form = "geometric";
  // Like the paper's data: the measured profile normalised over the whole sensor, seen only on
  // part of it.
  const std::vector<double> truth = Curve(TrueBits(options.dimension), m.output_positions);
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const double xi = m.output_positions[i];
    if (xi < kMeasuredFrom - 1e-9 || xi > kMeasuredTo + 1e-9) continue;
    RandomStream noise(options.seed, 999, i);
    m.measured.positions.push_back(xi);
    m.measured.values.push_back(std::max(0.0, truth[i] + 0.01 * noise.Normal()));
  }
  return m;
}

RunHistory MakeFakeHistory(const FakeRunOptions& options) {
  const RunMetadata metadata = MakeFakeMetadata(options);
  const auto d = static_cast<std::size_t>(options.dimension);
  // Least-squares distance to the measured points (paper Eq. 5), read off the output grid.
  auto distance = [&](const std::vector<double>& curve) {
    double squares = 0.0;
    for (std::size_t i = 0; i < metadata.measured.positions.size(); ++i) {
      const auto j = static_cast<std::size_t>(
          std::lround(metadata.measured.positions[i] / 0.9 * (options.points - 1)));
      squares += std::pow(curve[std::min(j, curve.size() - 1)] - metadata.measured.values[i], 2);
    }
    return squares / std::max<double>(1.0, static_cast<double>(metadata.measured.positions.size()));
  };
  auto median = [](std::vector<double> values) {
    std::sort(values.begin(), values.end());
    return values.empty() ? 1.0 : values[values.size() / 2];
  };
  // A small ABC-SMC of its own: thresholds at the median distance of the previous wave (a pilot
  // from the prior for wave 0), proposal = the previous wave's marginals kept inside [0.05, 0.95].
  std::vector<double> pilot;
  for (int i = 0; i < 2 * options.per_wave; ++i) {
    RandomStream stream(options.seed, 1000, static_cast<std::uint64_t>(i));
    std::vector<std::uint8_t> bits(d);
    for (auto& bit : bits) bit = stream.Uniform() < 0.5;
    pilot.push_back(distance(Curve(bits, metadata.output_positions)));
  }
  double threshold = median(pilot);
  std::vector<double> proposal(d, 0.5);
  RunHistory history;
  std::int64_t simulations = 0;
  for (int t = 0; t < options.waves; ++t) {
    WaveRecord wave;
    wave.wave = t;
    wave.thresholds = {threshold};
    wave.phi = 1.0;
    wave.proposal = proposal;
    if (options.pattern_classes && t > 0 && history.waves.back().particles.size() >= 2) {
      const auto& previous = history.waves.back().particles;
      wave.pattern_classes = {{previous[0].theta.bits, 0.6, 0.5, false},
                              {previous[1].theta.bits, 0.05, 1e-6, true}};
    }
    const std::int64_t budget = static_cast<std::int64_t>(options.per_wave) * 500;
    std::int64_t index = 0;
    for (; index < budget && static_cast<int>(wave.particles.size()) < options.per_wave; ++index) {
      RandomStream stream(
          options.seed, static_cast<std::uint64_t>(t), static_cast<std::uint64_t>(index));
      Particle p;
      p.index = index;
      for (double q : proposal) {
        const bool one = stream.Uniform() < q;
        p.theta.bits.push_back(one ? 1 : 0);
        p.log_weight += std::log(0.5) - std::log(one ? q : 1.0 - q);
      }
      // Later waves concentrate near 3e4 + 1e4 i, so that the reals' figures show a narrowing.
      for (const ContinuousParameter& parameter : metadata.reals) {
        const double centre = 3e4 + 1e4 * static_cast<double>(p.theta.reals.size());
        const double spread = 4e4 / (t + 1.0);
        p.theta.reals.push_back(std::clamp(
            centre + spread * (stream.Uniform() - 0.5), parameter.prior.low, parameter.prior.high));
      }
      std::vector<double> curve = Curve(p.theta.bits, metadata.output_positions);
      p.distance = {distance(curve), 1.0};
      if (p.distance[0] > threshold) continue;
      if (options.multi_fidelity) {
        p.low_distance = {1.1 * p.distance[0], 1.0};
        const auto k = wave.particles.size();
        p.confirmed = k % 3 == 0;
        const double confirmed_multipliers[] = {
            1.0, 1.0 / kFakeContinueIfRejected, 1.0 - 1.0 / kFakeContinueIfAccepted};
        p.multiplier = p.confirmed ? confirmed_multipliers[(k / 3) % 3] : 1.0;
      }
      if (options.outputs) p.output = std::move(curve);
      wave.particles.push_back(std::move(p));
    }
    wave.candidates = index;
    wave.complete = static_cast<int>(wave.particles.size()) == options.per_wave;
    if (options.moves && t > 0 && !history.waves.back().particles.empty()) {
      const auto& previous = history.waves.back().particles;
      for (std::size_t k = 0; k < wave.particles.size(); ++k) {
        wave.particles[k].ancestor = previous[k % previous.size()].index;
      }
      WaveMoves m;
      m.survivor_ess = 0.5 * static_cast<double>(previous.size());
      m.step = t == 1 ? 1.0 : 0.625;
      m.rounds = kFakeMoveRounds;
      m.proposed = kFakeMoveRounds * static_cast<std::int64_t>(wave.particles.size());
      m.accepted = m.proposed / 3;
      m.independent_proposed = m.proposed / 2;
      m.independent_accepted = m.accepted / 4;
      wave.moves = m;
    }
    wave.wall_seconds = 0.01 * static_cast<double>(index);
    if (options.multi_fidelity) {
      WaveFidelity f;
      f.continue_if_accepted = kFakeContinueIfAccepted;
      f.continue_if_rejected = kFakeContinueIfRejected;
      // The confirmed particles and about one in ten of the other candidates.
      f.expensive_simulations = static_cast<std::int64_t>((wave.particles.size() + 2) / 3) +
                                (index - static_cast<std::int64_t>(wave.particles.size())) / 10;
      f.cheap_seconds = 0.002 * static_cast<double>(index);
      f.expensive_seconds = 0.1 * static_cast<double>(f.expensive_simulations);
      f.next_continue_if_accepted = 0.9;
      f.next_continue_if_rejected = 0.2;
      f.cost_ratio = 50.0;
      wave.multi_fidelity = f;
    }
    ComputeWaveStatistics(wave, Estimator::kPaper);
    simulations += wave.candidates;
    std::vector<double> distances;
    for (const Particle& p : wave.particles) distances.push_back(p.distance[0]);
    threshold = median(distances);
    for (std::size_t k = 0; k < d; ++k) {
      proposal[k] = std::clamp(wave.marginals_paper[k], 0.05, 0.95);
    }
    const bool complete = wave.complete;
    history.waves.push_back(std::move(wave));
    if (!complete) break;
  }
  history.summary.termination = Termination::kMaxWaves;
  history.summary.message = "num_waves reached";
  history.summary.waves_completed = static_cast<int>(history.waves.size());
  history.summary.simulations = simulations;
  history.summary.wall_seconds = 0.01 * static_cast<double>(simulations);
  return history;
}

void RecordWave(SmcObserver& observer,
                const WaveRecord& wave,
                std::int64_t batch,
                int stop_after_batches) {
  WaveRecord start = wave;
  start.particles.clear();
  if (start.multi_fidelity) {
    WaveFidelity etas;
    etas.continue_if_accepted = wave.multi_fidelity->continue_if_accepted;
    etas.continue_if_rejected = wave.multi_fidelity->continue_if_rejected;
    start.multi_fidelity = etas;
  }
  // A resample-move wave knows its reweighting when it starts; its moves' counts when it ends.
  if (start.moves) start.moves = WaveMoves{wave.moves->survivor_ess, wave.moves->step};
  observer.OnWaveStart(start);
  std::size_t next = 0;
  std::int64_t accepted = 0;
  std::int64_t confirmed = 0;
  int batches = 0;
  for (std::int64_t begin = 0; begin < wave.candidates; begin += batch) {
    if (stop_after_batches >= 0 && batches == stop_after_batches) return;
    const std::int64_t end = std::min(begin + batch, wave.candidates);
    std::vector<Particle> in_batch;
    while (next < wave.particles.size() && wave.particles[next].index < end) {
      in_batch.push_back(wave.particles[next++]);
    }
    accepted += static_cast<std::int64_t>(in_batch.size());
    for (const Particle& p : in_batch) confirmed += p.confirmed ? 1 : 0;
    BatchProgress progress;
    progress.wave = wave.wave;
    progress.next_index = end;
    progress.accepted = accepted;
    progress.accepted_needed = static_cast<int>(wave.particles.size());
    progress.total_simulations = end;
    if (wave.multi_fidelity) {
      // The wave's costs in proportion to its candidates done; at its end, all of them.
      WaveFidelity f = *start.multi_fidelity;
      const double done = static_cast<double>(end) / static_cast<double>(wave.candidates);
      f.expensive_simulations = std::max(
          confirmed,
          static_cast<std::int64_t>(
              std::ceil(done * static_cast<double>(wave.multi_fidelity->expensive_simulations))));
      f.cheap_seconds = done * wave.multi_fidelity->cheap_seconds;
      f.expensive_seconds = done * wave.multi_fidelity->expensive_seconds;
      progress.fidelity = f;
    }
    observer.OnBatch(progress, in_batch);
    ++batches;
  }
  if (stop_after_batches >= 0) return;
  observer.OnWaveEnd(wave);
}

}  // namespace combabc::testing
