// Small runs with a population size per wave and each adaptive threshold schedule: the waves keep
// their n_t, and every eps_t is the schedule's rule applied to the previous wave as the history
// stores it (distances, importance weights, acceptance rate).
#include <gtest/gtest.h>

#include <cmath>

#include "checkpoints.hpp"
#include "combabc/samplers/combinatorial_smc.hpp"

namespace combabc {
namespace {

// y = theta + 0.5 e under theta ~ N(1, 2^2); the distance |y - 2|.
class GaussianSimulator : public Simulator {
 public:
  int output_size() const override { return 1; }
  void Simulate(const ParameterView& theta,
                RandomStream& rng,
                std::span<double> out) const override {
    out[0] = theta.reals[0] + 0.5 * rng.Normal();
  }
};

class AbsoluteDistance : public Distance {
 public:
  std::vector<DistanceComponent> components() const override {
    return {{"abs", ComponentKind::kThreshold, 1.0}};
  }
  void Evaluate(std::span<const double> y, std::span<double> out) const override {
    out[0] = std::abs(y[0] - 2.0);
  }
};

RunHistory RunGaussian(const SmcOptions& options,
                       SmcObserver* observer = nullptr,
                       const ResumePoint* resume = nullptr) {
  const ParameterSpace space(BinarySpace::Independent(0),
                             {{"theta", {.kind = PriorKind::kNormal, .mean = 1.0, .sd = 2.0}}});
  const GaussianSimulator sim;
  const AbsoluteDistance dist;
  return RunCombinatorialSmc({&space, &sim, &dist}, options, observer, resume);
}

SmcOptions Adaptive(ThresholdSchedule schedule) {
  SmcOptions o;
  o.num_waves = 4;
  o.accepted_per_wave = 300;
  o.seed = 11;
  schedule.initial = 4.0;
  o.thresholds = {schedule};
  return o;
}

// The previous wave's distances and importance weights.
struct Column {
  std::vector<double> d, w;
};
Column Of(const WaveRecord& wave) {
  Column c;
  for (const auto& p : wave.particles) {
    c.d.push_back(p.distance[0]);
    c.w.push_back(p.weight);
  }
  return c;
}

TEST(ScheduleRuns, PopulationSizePerWave) {
  SmcOptions o = Adaptive({});
  o.accepted_by_wave = {600, 200, 200, 400};
  const RunHistory h = RunGaussian(o);
  ASSERT_EQ(h.waves.size(), 4U);
  for (std::size_t t = 0; t < 4; ++t) {
    EXPECT_EQ(static_cast<int>(h.waves[t].particles.size()), o.accepted_by_wave[t]) << t;
    EXPECT_TRUE(h.waves[t].complete);
  }
  // Resumed from a checkpoint inside the second wave and between waves: the same history.
  o.batch_size = 64;
  testing::Checkpoints checkpoints;
  const RunHistory whole = RunGaussian(o, &checkpoints);
  ASSERT_GT(checkpoints.points.size(), 12U);
  for (const std::size_t i : {std::size_t{11}, checkpoints.points.size() - 2}) {
    const RunHistory resumed = RunGaussian(o, nullptr, &checkpoints.points[i]);
    ASSERT_EQ(resumed.waves.size(), whole.waves.size()) << i;
    for (std::size_t t = 0; t < whole.waves.size(); ++t) {
      ASSERT_EQ(resumed.waves[t].particles.size(), whole.waves[t].particles.size()) << i;
      for (std::size_t k = 0; k < whole.waves[t].particles.size(); ++k) {
        EXPECT_EQ(resumed.waves[t].particles[k].theta.reals,
                  whole.waves[t].particles[k].theta.reals);
      }
    }
  }
  std::string why;
  o.accepted_by_wave = {600, 200};
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why,
            "SmcOptions::accepted_by_wave has 2 entries; must have one per wave (num_waves = 4)");
  o.accepted_by_wave = {600, 0, 1, 1};
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "SmcOptions::accepted_by_wave[1] = 0; must be >= 1");
}

TEST(ScheduleRuns, WeightedQuantile) {
  ThresholdSchedule s;
  s.quantile = 0.5;
  s.weighted = true;
  const RunHistory h = RunGaussian(Adaptive(s));
  ASSERT_EQ(h.waves.size(), 4U);
  for (std::size_t t = 1; t < h.waves.size(); ++t) {
    const Column c = Of(h.waves[t - 1]);
    EXPECT_EQ(h.waves[t].thresholds[0], WeightedQuantile(c.d, c.w, 0.5)) << t;
  }
}

TEST(ScheduleRuns, AcceptanceRate) {
  ThresholdSchedule s;
  s.kind = ThresholdKind::kAcceptance;
  s.acceptance_rate = 0.2;
  const RunHistory h = RunGaussian(Adaptive(s));
  ASSERT_EQ(h.waves.size(), 4U);
  for (std::size_t t = 1; t < h.waves.size(); ++t) {
    const Column c = Of(h.waves[t - 1]);
    const double alpha = std::min(1.0, 0.2 / h.waves[t - 1].acceptance_rate);
    EXPECT_EQ(h.waves[t].thresholds[0], EmpiricalQuantile(c.d, alpha)) << t;
    EXPECT_LT(h.waves[t].thresholds[0], h.waves[t - 1].thresholds[0]) << t;
    std::printf("wave %zu: eps %.4f, acceptance rate %.3f (target 0.2)\n",
                t + 1,
                h.waves[t].thresholds[0],
                h.waves[t].acceptance_rate);
  }
}

TEST(ScheduleRuns, EffectiveSampleSize) {
  ThresholdSchedule s;
  s.kind = ThresholdKind::kEss;
  s.ess_fraction = 0.5;
  const RunHistory h = RunGaussian(Adaptive(s));
  ASSERT_EQ(h.waves.size(), 4U);
  for (std::size_t t = 1; t < h.waves.size(); ++t) {
    const Column c = Of(h.waves[t - 1]);
    EXPECT_EQ(h.waves[t].thresholds[0], EssThreshold(c.d, c.w, 0.5)) << t;
    EXPECT_LT(h.waves[t].thresholds[0], h.waves[t - 1].thresholds[0]) << t;
  }
}

}  // namespace
}  // namespace combabc
