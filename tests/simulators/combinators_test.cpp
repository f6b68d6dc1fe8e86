// The simulator combinators (src/simulators/): experiments run one after the other with their
// outputs concatenated, and a cheap simulator's outputs picked to stand for an expensive one's.
#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "combabc/core/batch_failures.hpp"
#include "combabc/rng/random_stream.hpp"
#include "simulators/experiments_simulator.hpp"
#include "simulators/selected_outputs.hpp"

namespace combabc {
namespace {

// Output k = offset + k + bit 0; fails the candidates whose bit 1 is set when `fails`.
class Ramp : public Simulator {
 public:
  Ramp(int size, double offset, bool fails) : size_(size), offset_(offset), fails_(fails) {}
  int output_size() const override { return size_; }
  void Simulate(const ParameterView& theta, RandomStream&, std::span<double> out) const override {
    if (fails_ && theta.bits[1] != 0) throw SimulationFailed("ramp " + std::to_string(offset_));
    for (int k = 0; k < size_; ++k) out[static_cast<std::size_t>(k)] = offset_ + k + theta.bits[0];
  }

 private:
  int size_;
  double offset_;
  bool fails_;
};

struct Batch {
  std::vector<std::uint8_t> bits = {1, 0, 0, 1};  // two candidates of two bits
  std::vector<RandomStream> rngs = {RandomStream(1, 0, 0), RandomStream(1, 0, 1)};
  std::vector<std::uint8_t> status = std::vector<std::uint8_t>(2, 0);
  std::vector<char> reasons = std::vector<char>(2 * kFailureReasonBytes, '\0');
  BatchFailures failures{status, reasons};
  ParameterBatch view() const {
    return {.count = 2, .num_bits = 2, .num_reals = 0, .bits = bits, .reals = {}};
  }
};

TEST(Combinators, ExperimentsConcatenateAndTheFirstFailureStays) {
  std::vector<std::unique_ptr<Simulator>> parts;
  parts.push_back(std::make_unique<Ramp>(2, 10.0, false));
  parts.push_back(std::make_unique<Ramp>(1, 20.0, true));
  parts.push_back(std::make_unique<Ramp>(1, 30.0, true));
  const ExperimentsSimulator experiments(std::move(parts));
  ASSERT_EQ(experiments.output_size(), 4);
  Batch b;
  std::vector<double> out(8, -1.0);
  experiments.SimulateBatch(b.view(), b.rngs, out, b.failures);
  EXPECT_FALSE(b.failures.failed(0));
  EXPECT_EQ(std::vector<double>(out.begin(), out.begin() + 4),
            (std::vector<double>{11.0, 12.0, 21.0, 31.0}));
  ASSERT_TRUE(b.failures.failed(1));
  EXPECT_NE(b.failures.reason(1).find("ramp 20"), std::string::npos);
}

TEST(Combinators, SelectedOutputsPickTheInnerOutputs) {
  const SelectedOutputs selected(std::make_unique<Ramp>(5, 0.0, false), {4, 0, 2});
  ASSERT_EQ(selected.output_size(), 3);
  Batch b;
  std::vector<double> out(6, -1.0);
  selected.SimulateBatch(b.view(), b.rngs, out, b.failures);
  EXPECT_EQ(out, (std::vector<double>{5.0, 1.0, 3.0, 4.0, 0.0, 2.0}));
  std::vector<double> one(3, -1.0);
  RandomStream rng(1, 0, 0);
  selected.Simulate(b.view()[0], rng, one);
  EXPECT_EQ(one, (std::vector<double>{5.0, 1.0, 3.0}));
}

}  // namespace
}  // namespace combabc
