// The reference workers shipped in examples/custom-simulator speak the protocol and compute the
// same model: the Python one (worker.py, the README's) and the C++ one (worker.cpp).
#include <gtest/gtest.h>

#include <string>

#include "combabc/simulators/worker_simulator.hpp"
#include "simulators/simulator_test_support.hpp"
#include "support/test_support.hpp"

namespace combabc::testing {
namespace {

TEST(ReferenceWorkers, PythonAndCppAgreeOnEveryConfiguration) {
  RunFolder run("reference");
  ExternalSimulatorOptions o;
  o.config_directory = std::string(COMBABC_SOURCE_DIR) + "/examples/custom-simulator";
  o.work_directory = run / "history.work";
  o.bit_names = {"1", "2", "3", "4", "5", "6"};
  o.output_size = 21;
  o.argv = {"python3", "{config_dir}/worker.py"};
  const WorkerSimulator python(o);
  o.argv = {COMBABC_CPP_WORKER};
  const WorkerSimulator cpp(o);
  EXPECT_EQ(python.handshake(), "combabc-worker 2 21 example-supports 1.0");
  EXPECT_EQ(cpp.handshake(), "combabc-worker 2 21 example-supports-cpp 1.0");
  RandomStream rng(1, 0, 0);
  std::vector<double> a(21);
  std::vector<double> b(21);
  for (int code = 0; code < 64; code += 7) {
    Candidate c;
    for (int k = 0; k < 6; ++k) c.bits.push_back(static_cast<std::uint8_t>((code >> k) & 1));
    python.Simulate(c.view(), rng, a);
    cpp.Simulate(c.view(), rng, b);
    ExpectNear(a, b, 1e-12, "configuration " + std::to_string(code) + ", outputs");
    EXPECT_GE(a[0], 0.05);
  }
  // The model responds to its bits: all fixed is the flat baseline.
  Candidate fixed;
  fixed.bits.assign(6, 1);
  python.Simulate(fixed.view(), rng, a);
  EXPECT_EQ(a, std::vector<double>(21, 0.05));
}

}  // namespace
}  // namespace combabc::testing
