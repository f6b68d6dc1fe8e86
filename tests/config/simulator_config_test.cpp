// [simulator]: the sensor by default (declaring its clamps and output positions), command and
// worker simulators declaring bits and outputs, and every mistake located at its key.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "combabc/config/config.hpp"
#include "combabc/core/error.hpp"
#include "config/config_error.hpp"
#include "support/test_support.hpp"

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

const std::string kWorker =
    "[simulator]\n"
    "kind = \"worker\"\n"
    "argv = [\"python3\", \"{config_dir}/w.py\"]\n"
    "timeout = 2.5\n"
    "[simulator.bits]\n"
    "names = [\"a\", \"b\", \"c\"]\n"
    "[simulator.outputs]\n"
    "name = \"strain\"\n"
    "coordinates = [0.0, 0.1, 0.2]\n";

using testing::ConfigErrorOf;

TEST(SimulatorConfig, TheSensorIsTheDefaultAndDeclaresItsClampsAndPositions) {
  const CalibrationConfig c = ParseConfig("[model.clamps]\nper_edge = 3\n" + kRest, "run.toml");
  EXPECT_EQ(c.simulator.kind, SimulatorKind::kSensor);
  EXPECT_EQ(c.simulator.outputs.coordinates, c.model.load_cases[0].output_positions);
  EXPECT_EQ(c.space.dimension, 6);
  EXPECT_EQ(c.space.names.front(), "clamp 1");
  // Where the bits are set, for refusals of the space's size (enumerate's 2^24).
  EXPECT_EQ(c.bits_key, "model.clamps.per_edge");
  EXPECT_EQ(c.bits_line, 2);
  EXPECT_EQ(ConfigErrorOf("[simulator]\nkind = \"sensor\"\nargv = [\"x\"]\n" + kRest)
                .find("dir/run.toml:3: simulator.argv: unknown key"),
            0u);
}

TEST(SimulatorConfig, AWorkerDeclaresItsBitsOutputsAndParameters) {
  const CalibrationConfig c = ParseConfig(kWorker + kRest +
                                              "[sampler]\nestimator = \"importance\"\n"
                                              "[parameters.\"my gain\"]\nprior = \"uniform\"\n"
                                              "low = -1e30\nhigh = 1e30\n",
                                          "dir/run.toml");
  EXPECT_EQ(c.simulator.kind, SimulatorKind::kWorker);
  EXPECT_EQ(c.space.dimension, 3);
  EXPECT_EQ(c.space.names, (std::vector<std::string>{"a", "b", "c"}));
  EXPECT_EQ(c.bits_key, "simulator.bits.names");
  EXPECT_EQ(c.bits_line, 6);
  EXPECT_EQ(c.simulator.outputs.name, "strain");
  EXPECT_EQ(c.simulator.outputs.coordinates, (std::vector<double>{0.0, 0.1, 0.2}));
  const ExternalSimulatorOptions& e = c.simulator.external;
  EXPECT_EQ(e.argv, (std::vector<std::string>{"python3", "{config_dir}/w.py"}));
  EXPECT_EQ(e.timeout_s, 2.5);
  EXPECT_EQ(e.output_size, 3);
  EXPECT_EQ(e.real_names, std::vector<std::string>{"my gain"});
  EXPECT_EQ(e.config_directory, "dir");
}

// No [simulator.bits] (or count = 0): a continuous-only space, which needs a real parameter.
TEST(SimulatorConfig, ASimulatorWithoutBitsCalibratesItsRealParameters) {
  const std::string head =
      "[simulator]\n"
      "kind = \"command\"\n"
      "argv = [\"sh\", \"{config_dir}/m.sh\", \"{params}\"]\n"
      "[simulator.outputs]\n"
      "name = \"y\"\n"
      "coordinates = [0.0, 0.1, 0.2]\n";
  const std::string real =
      "[sampler]\nestimator = \"importance\"\n"
      "[parameters.mu]\nprior = \"normal\"\nmean = 0.0\nsd = 1.0\n";
  for (const std::string& bits : {std::string(), std::string("[simulator.bits]\ncount = 0\n")}) {
    std::string text = head;
    text += bits;
    text += kRest;
    text += real;
    const CalibrationConfig c = ParseConfig(text, "dir/run.toml");
    EXPECT_EQ(c.space.dimension, 0);
    EXPECT_TRUE(c.space.names.empty());
    EXPECT_TRUE(c.simulator.external.bit_names.empty());
    EXPECT_EQ(c.simulator.external.real_names, std::vector<std::string>{"mu"});
    std::string why;
    EXPECT_TRUE(c.space.IsValid(&why)) << why;
  }
  EXPECT_EQ(ConfigErrorOf(head + kRest)
                .find("dir/run.toml:1: simulator.bits: the simulator has no "
                      "parameters to calibrate"),
            0u)
      << ConfigErrorOf(head + kRest);
  EXPECT_NE(ConfigErrorOf(head + "[simulator.bits]\ncount = -1\n" + kRest + real)
                .find("simulator.bits.count: must be in [0, 4096]"),
            std::string::npos);
}

TEST(SimulatorConfig, CoordinatesFromACsvFile) {
  const testing::TempFolder dir("coords");
  // The data CSV's dialect (issue 20, D8): a quoted coordinate and a comment holding commas.
  std::ofstream(dir / "c.csv") << "x_m,comment\r\n0.0,a\r\n\"0.05\",\"c, d\"\r\n\r\n0.2,b\r\n";
  std::string text = kWorker;
  text.replace(text.find("coordinates = [0.0, 0.1, 0.2]"),
               std::string("coordinates = [0.0, 0.1, 0.2]").size(),
               "coordinates_csv = \"c.csv\"");
  const CalibrationConfig c = ParseConfig(text + kRest, dir / "run.toml");
  EXPECT_EQ(c.simulator.outputs.coordinates, (std::vector<double>{0.0, 0.05, 0.2}));
  std::ofstream(dir / "c.csv") << "x\n0.0\nzero\n";
  try {
    ParseConfig(text + kRest, dir / "run.toml");
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kData);
    EXPECT_EQ(e.line(), 3);
    EXPECT_NE(std::string(e.what()).find("'zero' is not a number"), std::string::npos);
  }
  std::ofstream(dir / "c.csv") << "x,note\n0.0,a\n0.1,b, c\n";
  try {
    ParseConfig(text + kRest, dir / "run.toml");
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kData);
    EXPECT_NE(std::string(e.what()).find("c.csv:3:3: row has 3 cells; the first row has 2"),
              std::string::npos)
        << e.what();
  }
}

TEST(SimulatorConfig, MistakesAreLocatedAtTheirKey) {
  auto with = [](const std::string& from, const std::string& to) {
    std::string text = kWorker;
    text.replace(text.find(from), from.size(), to);
    return text + kRest;
  };
  EXPECT_EQ(ConfigErrorOf("[model]\nlength = 1\n" + kWorker + kRest)
                .rfind("dir/run.toml:1: model: [model] configures the built-in sensor", 0),
            0u);
  EXPECT_NE(ConfigErrorOf(with("kind = \"worker\"", "kind = \"shell\""))
                .find("simulator.kind: unknown simulator kind 'shell'; expected one of \"sensor\", "
                      "\"command\", \"worker\""),
            std::string::npos);
  EXPECT_NE(ConfigErrorOf(with("argv = [\"python3\", \"{config_dir}/w.py\"]\n", ""))
                .find("simulator.argv: missing required key"),
            std::string::npos);
  EXPECT_NE(ConfigErrorOf(with("kind = \"worker\"", "kind = \"command\""))
                .find("simulator.argv: argv has no {params}"),
            std::string::npos);
  EXPECT_NE(ConfigErrorOf(with("names = [\"a\", \"b\", \"c\"]", "names = [\"a\", \"a\"]"))
                .find("simulator.bits.names: 'a' appears twice"),
            std::string::npos);
  EXPECT_NE(ConfigErrorOf(with("[0.0, 0.1, 0.2]", "[0.0, 0.2, 0.1]"))
                .find("simulator.outputs.coordinates: must be strictly increasing (entry 2)"),
            std::string::npos);
  EXPECT_NE(ConfigErrorOf(with("timeout = 2.5", "params = \"file\""))
                .find("simulator.params: unknown key"),
            std::string::npos)
      << "params is a command key";
  // The Gaussian extension's default centre is the sensor's load: another simulator must say.
  EXPECT_NE(ConfigErrorOf(kWorker + kRest + "[data.gaussian_extension]\nfit_points = 3\n")
                .find("data.gaussian_extension.impact_position: missing required key"),
            std::string::npos);
}

}  // namespace
}  // namespace combabc
