// Runs a tiny combinatorial ABC-SMC through the installed package and checks it found the target.
#include <cmath>
#include <cstdio>

#include "combabc/samplers/combinatorial_smc.hpp"

namespace {

class Echo : public combabc::Simulator {
 public:
  int output_size() const override { return 3; }
  void Simulate(const combabc::ParameterView& theta,
                combabc::RandomStream&,
                std::span<double> out) const override {
    for (int k = 0; k < 3; ++k) out[k] = theta.bits[k];
  }
};

class ToTarget : public combabc::Distance {
 public:
  std::vector<combabc::DistanceComponent> components() const override { return {{"l1"}}; }
  void Evaluate(std::span<const double> y, std::span<double> out) const override {
    out[0] = std::abs(y[0] - 1) + std::abs(y[1]) + std::abs(y[2] - 1);
  }
};

}  // namespace

int main() {
  const combabc::ParameterSpace space(combabc::BinarySpace::Independent(3));
  Echo sim;
  ToTarget dist;
  const auto h = combabc::RunRejection({&space, &sim, &dist}, 50, {0.0}, 1);
  const auto& m = h.waves[0].marginals_paper;
  std::printf("%s; marginals %.2f %.2f %.2f\n", h.summary.BriefReport().c_str(), m[0], m[1], m[2]);
  // Every accepted particle is (1, 0, 1); the marginals are sums of 1/50, so compare to round-off.
  const bool found = std::abs(m[0] - 1) < 1e-12 && m[1] == 0.0 && std::abs(m[2] - 1) < 1e-12;
  return found ? 0 : 1;
}
