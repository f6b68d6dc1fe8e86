// [simulator.low_fidelity] and [sampler.multi_fidelity]: a cheap sensor over [model] (whatever
// the expensive simulator is), an external cheap simulator whose outputs are mapped onto the
// expensive one's by coordinate, and every mistake located at its key.
#include <gtest/gtest.h>

#include <string>

#include "combabc/config/config.hpp"
#include "combabc/core/error.hpp"
#include "config/config_error.hpp"

namespace combabc {
namespace {

const std::string kRest =
    "[data]\n"
    "csv = \"p.csv\"\n"
    "position_unit = \"m\"\n"
    "[metric]\n"
    "[[metric.component]]\n"
    "type = \"least_squares\"\n"
    "window = [0.0, 0.2]\n";

// An expensive command simulator with 4 bits and 3 outputs.
const std::string kCommand =
    "[simulator]\n"
    "kind = \"command\"\n"
    "argv = [\"python3\", \"{config_dir}/fe.py\", \"{params}\"]\n"
    "[simulator.bits]\n"
    "count = 4\n"
    "[simulator.outputs]\n"
    "coordinates = [0.1, 0.2, 0.3]\n";

using testing::ConfigErrorOf;

TEST(LowFidelityConfig, ACheapSensorOfTheSensorWithACoarserMeshAndItsOptions) {
  const CalibrationConfig c = ParseConfig(
      "[model.clamps]\nper_edge = 3\n[model.mesh]\nelements_per_section = 4\n"
      "[simulator.low_fidelity]\nkind = \"sensor\"\n"
      "[simulator.low_fidelity.model]\ntheory = \"fsdt\"\n"
      "[simulator.low_fidelity.model.mesh]\nelements_per_section = 1\n"
      "[sampler]\n[sampler.multi_fidelity]\ncontinue_if_accepted = 0.5\n"
      "continue_if_rejected = 0.2\nadapt = false\nfloor = 0.05\ncost_ratio = 20\n" +
          kRest,
      "run.toml");
  ASSERT_TRUE(c.low_fidelity.has_value());
  const LowFidelityConfig& low = *c.low_fidelity;
  EXPECT_EQ(low.simulator.kind, SimulatorKind::kSensor);
  EXPECT_EQ(low.model.elements_per_section, 1);
  EXPECT_EQ(low.model.theory, plate::PlateTheory::kFsdt);
  EXPECT_EQ(low.model.clamps_per_edge, 3);  // from [model]
  EXPECT_EQ(c.model.elements_per_section, 4);
  EXPECT_NE(c.model.theory, plate::PlateTheory::kFsdt);
  // Its outputs are the expensive simulator's: each one maps onto itself.
  ASSERT_EQ(low.output_map.size(), c.simulator.outputs.coordinates.size());
  for (std::size_t k = 0; k < low.output_map.size(); ++k) {
    EXPECT_EQ(low.output_map[k], static_cast<int>(k));
  }
  const std::vector<SensorModelPlan> plans = LowFidelitySensorModels(c);
  ASSERT_EQ(plans.size(), 1u);
  EXPECT_EQ(plans[0].options.load_cases[0].output_positions, c.simulator.outputs.coordinates);
  const MultiFidelityOptions& mf = c.smc.multi_fidelity;
  EXPECT_EQ(mf.continue_if_accepted, 0.5);
  EXPECT_EQ(mf.continue_if_rejected, 0.2);
  EXPECT_FALSE(mf.adapt);
  EXPECT_EQ(mf.floor, 0.05);
  EXPECT_EQ(mf.cost_ratio, 20.0);
  // Without the table: a single-fidelity run.
  EXPECT_FALSE(ParseConfig(kRest, "run.toml").low_fidelity.has_value());
}

// A multi-fidelity wave keeps up to kMultiFidelityParticlesPerAccepted particles per one it needs
// (the engine stops it there), and the memory estimate counts them: 10 waves of 100,000 fit in
// 1 GB single-fidelity (0.2 GB of particles), not with a cheap model (4.72 GB).
TEST(LowFidelityConfig, TheMemoryEstimateCountsTheParticlesAWaveMayKeep) {
  const std::string sampler = "[sampler]\nbatch_size = 8\nwaves = 10\naccepted_per_wave = 100000\n";
  const std::string cheap =
      "[simulator.low_fidelity]\nkind = \"command\"\nargv = [\"c\", \"{params}\"]\n"
      "[simulator.low_fidelity.bits]\ncount = 4\n"
      "[simulator.low_fidelity.outputs]\ncoordinates = [0.1, 0.2, 0.3]\n";
  const std::string limit = "memory_limit_gb = 1\n";
  EXPECT_EQ(ConfigErrorOf(limit + kCommand + sampler + kRest), "no error");
  const std::string e = ConfigErrorOf(limit + kCommand + sampler + cheap + kRest);
  EXPECT_EQ(e.rfind("dir/run.toml:12: sampler.accepted_per_wave: is 100000; the run would need "
                    "about 4.72 GB",
                    0),
            0u)
      << e;
  EXPECT_NE(e.find("a multi-fidelity wave keeps up to 20 x accepted_per_wave"), std::string::npos)
      << e;
}

TEST(LowFidelityConfig, ACheapSensorOfACommandNeedsNoOutputDeclaration) {
  const CalibrationConfig c = ParseConfig(
      "[model.clamps]\nper_edge = 2\n" + kCommand + "[simulator.low_fidelity]\n" + kRest,
      "run.toml");
  ASSERT_TRUE(c.low_fidelity.has_value());
  EXPECT_EQ(c.low_fidelity->simulator.kind, SimulatorKind::kSensor);  // the default kind
  EXPECT_EQ(c.low_fidelity->output_map, (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(LowFidelitySensorModels(c)[0].options.load_cases[0].output_positions,
            (std::vector<double>{0.1, 0.2, 0.3}));
}

TEST(LowFidelityConfig, AnExternalCheapSimulatorsOutputsAreMappedByCoordinate) {
  const CalibrationConfig c = ParseConfig(
      kCommand +
          "[simulator.low_fidelity]\nkind = \"worker\"\nargv = [\"python3\", \"cheap.py\"]\n"
          "[simulator.low_fidelity.bits]\ncount = 4\n"
          "[simulator.low_fidelity.outputs]\ncoordinates = [0.0, 0.1, 0.15, 0.2, "
          "0.3000000000001]\n" +
          kRest,
      "run.toml");
  ASSERT_TRUE(c.low_fidelity.has_value());
  const LowFidelityConfig& low = *c.low_fidelity;
  EXPECT_EQ(low.simulator.kind, SimulatorKind::kWorker);
  EXPECT_EQ(low.simulator.external.output_size, 5);
  EXPECT_EQ(low.output_map, (std::vector<int>{1, 3, 4}));  // the extra two are dropped
}

TEST(LowFidelityConfig, MistakesAreLocatedAtTheirKey) {
  const std::string sensor = "[model.clamps]\nper_edge = 2\n";
  const std::string cheap_worker =
      "[simulator.low_fidelity]\nkind = \"worker\"\nargv = [\"w\"]\n"
      "[simulator.low_fidelity.bits]\ncount = 4\n[simulator.low_fidelity.outputs]\n";
  // Outputs that miss an expensive coordinate.
  EXPECT_EQ(ConfigErrorOf(kCommand + cheap_worker + "coordinates = [0.1, 0.3]\n" + kRest)
                .rfind("dir/run.toml:13: simulator.low_fidelity.outputs: has no output at 0.2", 0),
            0u);
  // Other bits.
  EXPECT_EQ(
      ConfigErrorOf(
          sensor + kCommand +
          "[simulator.low_fidelity]\n[simulator.low_fidelity.model.clamps]\nper_edge = 3\n" + kRest)
          .rfind("dir/run.toml:12: simulator.low_fidelity.model.clamps.per_edge: the cheap "
                 "sensor has 6 clamps",
                 0),
      0u);
  EXPECT_EQ(
      ConfigErrorOf(kCommand +
                    "[simulator.low_fidelity]\nkind = \"command\"\nargv = [\"c\", \"{params}\"]\n"
                    "[simulator.low_fidelity.bits]\ncount = 5\n"
                    "[simulator.low_fidelity.outputs]\ncoordinates = [0.1, 0.2, 0.3]\n" +
                    kRest)
          .rfind("dir/run.toml:12: simulator.low_fidelity.bits.count: declares 5 bits; the "
                 "run has 4",
                 0),
      0u);
  // Outputs off the cheap sensor's plate.
  std::string far = kCommand;
  far.replace(far.find("0.3]"), 4, "1.5]");
  EXPECT_NE(ConfigErrorOf(sensor + far + "[simulator.low_fidelity]\n" + kRest)
                .find("dir/run.toml:10: simulator.low_fidelity.kind: the expensive simulator's "
                      "output at 1.5"),
            std::string::npos);
  // Unknown keys, in the table and in its model.
  EXPECT_EQ(ConfigErrorOf("[simulator.low_fidelity]\nspeed = 2\n" + kRest)
                .rfind("dir/run.toml:2: simulator.low_fidelity.speed: unknown key", 0),
            0u);
  EXPECT_EQ(ConfigErrorOf("[simulator.low_fidelity.model]\nlenght = 2\n" + kRest)
                .rfind("dir/run.toml:2: simulator.low_fidelity.model.lenght: unknown key", 0),
            0u);
  EXPECT_EQ(ConfigErrorOf("[simulator.low_fidelity.model.load]\nx = 0.2\n" + kRest)
                .rfind("dir/run.toml:1: simulator.low_fidelity.model.load: the cheap sensor "
                       "simulates the run's experiments",
                       0),
            0u);
  EXPECT_EQ(ConfigErrorOf(kCommand + "[simulator.low_fidelity]\nkind = \"shell\"\n" + kRest)
                .rfind("dir/run.toml:9: simulator.low_fidelity.kind: unknown simulator kind", 0),
            0u);
  // [sampler.multi_fidelity]: ranges, and no options without a cheap simulator.
  const std::string low = "[simulator.low_fidelity]\n";
  for (const std::string bad :
       {"continue_if_accepted = 0", "continue_if_rejected = 1.5", "floor = 0", "floor = -0.1"}) {
    const std::string key = bad.substr(0, bad.find(' '));
    std::string text = low;
    text += "[sampler.multi_fidelity]\n";
    text += bad;
    text += "\n";
    text += kRest;
    EXPECT_EQ(ConfigErrorOf(text).rfind(
                  "dir/run.toml:3: sampler.multi_fidelity." + key + ": must be in (0, 1]", 0),
              0u)
        << bad;
  }
  EXPECT_EQ(
      ConfigErrorOf(low + "[sampler.multi_fidelity]\ncost_ratio = 0\n" + kRest)
          .rfind("dir/run.toml:3: sampler.multi_fidelity.cost_ratio: must be finite and > 0", 0),
      0u);
  EXPECT_EQ(ConfigErrorOf(low + "[sampler.multi_fidelity]\nslack = 1\n" + kRest)
                .rfind("dir/run.toml:3: sampler.multi_fidelity.slack: unknown key", 0),
            0u);
  EXPECT_EQ(ConfigErrorOf("[sampler.multi_fidelity]\nfloor = 0.1\n" + kRest)
                .rfind("dir/run.toml:1: sampler.multi_fidelity: multi-fidelity options need a "
                       "cheap simulator: add [simulator.low_fidelity]",
                       0),
            0u);
  // Moves leave one simulator's target invariant: not a multi-fidelity run's.
  EXPECT_EQ(
      ConfigErrorOf(low + "[sampler]\nmethod = \"resample_move\"\n" + kRest)
          .rfind("dir/run.toml:3: sampler.method: moves do not apply to multi-fidelity runs", 0),
      0u);
  // [model] beside an external simulator only configures a cheap sensor.
  EXPECT_EQ(ConfigErrorOf("[model]\nlength = 1\n" + kCommand + kRest)
                .rfind("dir/run.toml:1: model: [model] configures the built-in sensor", 0),
            0u);
  EXPECT_EQ(ConfigErrorOf("[model]\nlength = 1\n" + sensor + kCommand + low + kRest), "no error");
}

}  // namespace
}  // namespace combabc
