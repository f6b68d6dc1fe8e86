// The run fingerprint (src/services/steps/run_fingerprint.*): what counts in it and what does
// not, and the legacy reading of a sensor run written before RZT became the default.
#include <gtest/gtest.h>

#include <optional>
#include <string>
#include <vector>

#include "combabc/params/binary_space.hpp"
#include "combabc/params/parameter_space.hpp"
#include "services/steps/run_fingerprint.hpp"

namespace combabc::services {
namespace {

std::string Part(const Fingerprint& f, const std::string& name) {
  for (const auto& [part, digest] : f) {
    if (part == name) return digest;
  }
  return {};
}

struct ProblemFingerprint {
  SmcOptions options;
  ParameterSpace space{BinarySpace::Independent(4)};
  std::vector<double> observed{1.0, 2.0, 3.0};

  Fingerprint Compute() const {
    ProblemFingerprintInputs in;
    in.options = &options;
    in.space = &space;
    in.observed = observed;
    in.components = {{.name = "l2"}};
    in.calling = {{"function", "model"}};
    in.version = "test";
    return ComputeProblemFingerprint(in);
  }
};

TEST(Fingerprint, StopLimitsDoNotCountTheDataDoes) {
  ProblemFingerprint a;
  const Fingerprint before = a.Compute();
  ASSERT_EQ(Part(before, "combined").size(), 16u);
  a.options.max_simulations = 1000;
  a.options.min_acceptance_rate = 0.01;
  EXPECT_EQ(a.Compute(), before);  // a resume may raise them
  a.observed[1] = 2.5;
  const Fingerprint after = a.Compute();
  EXPECT_NE(Part(after, "data"), Part(before, "data"));
  EXPECT_NE(Part(after, "combined"), Part(before, "combined"));
  EXPECT_EQ(Part(after, "sampler"), Part(before, "sampler"));
  EXPECT_EQ(Part(after, "space"), Part(before, "space"));
}

TEST(Fingerprint, SameFingerprintIgnoresTheOrderOfParts) {
  const Fingerprint a = {{"data", "01"}, {"space", "02"}};
  EXPECT_TRUE(SameFingerprint(a, {{"space", "02"}, {"data", "01"}}));
  EXPECT_FALSE(SameFingerprint(a, {{"space", "02"}, {"data", "03"}}));
  EXPECT_FALSE(SameFingerprint(a, {{"data", "01"}}));
}

// A stand-in for the fingerprint of a config: only the theory counts.
Fingerprint TheoryPart(const CalibrationConfig& c) {
  return {{"simulator", c.model.theory == plate::PlateTheory::kKirchhoff ? "kirchhoff" : "rzt"}};
}

TEST(Fingerprint, LegacyReadingIsKirchhoffWhenOnlyThatMatches) {
  CalibrationConfig config;
  config.simulator.kind = SimulatorKind::kSensor;
  config.model.theory = plate::PlateTheory::kRzt;
  const Fingerprint now = TheoryPart(config);
  const std::optional<CalibrationConfig> old =
      LegacyReading(config, now, {{"simulator", "kirchhoff"}}, TheoryPart);
  ASSERT_TRUE(old.has_value());
  EXPECT_EQ(old->model.theory, plate::PlateTheory::kKirchhoff);
  // Today's reading matches, or neither does: no legacy reading.
  EXPECT_FALSE(LegacyReading(config, now, now, TheoryPart));
  EXPECT_FALSE(LegacyReading(config, now, {{"simulator", "other"}}, TheoryPart));
  // Only the sensor had that default.
  config.simulator.kind = SimulatorKind::kCommand;
  EXPECT_FALSE(LegacyReading(config, now, {{"simulator", "kirchhoff"}}, TheoryPart));
}

}  // namespace
}  // namespace combabc::services
