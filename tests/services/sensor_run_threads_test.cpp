// The built-in sensor simulator in a whole run through the services (config, precompute,
// executor, metric, history), on two threads: the same history as on one. This is the
// ThreadSanitizer's run of the services' threaded path; the CLI's end-to-end calibration
// (tests/e2e/calibration_test.cpp: the default sensor, 10 waves of 300) checks the posterior in
// Release, and under ThreadSanitizer took 89 s and a build of the CLI (docs/ci.md).
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "combabc/samplers/run_history.hpp"
#include "combabc/services/run.hpp"
#include "e2e/tiny_sensor.hpp"
#include "support/test_support.hpp"

namespace combabc::testing {
namespace {

RunHistory RunWithThreads(const TempFolder& dir, int threads) {
  services::RunRequest request;
  request.config_path = dir / "config.toml";
  request.output_directory = dir / ("threads-" + std::to_string(threads));
  request.threads = threads;
  request.report = false;
  return services::RunCalibration(request).history;
}

TEST(SensorRunThreads, SameHistoryForTwoThreadsAsForOne) {
  const TempFolder dir("sensor-run-threads");
  WriteTinySensorData(dir.path());
  std::ofstream(dir / "config.toml") << TinySensorConfig(
      "seed = 7\nwaves = 3\naccepted_per_wave = 100\nestimator = \"importance\"\n");
  // Two threads first: the precompute is built on the run's pool, then cached for the other.
  const RunHistory two = RunWithThreads(dir, 2);
  const RunHistory one = RunWithThreads(dir, 1);
  ASSERT_EQ(one.waves.size(), 3u);
  std::string where;
  EXPECT_TRUE(SameHistory(one, two, &where)) << where;
}

}  // namespace
}  // namespace combabc::testing
