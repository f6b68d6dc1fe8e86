#pragma once
// The simulator f_theta: from a parameter vector to an output vector Y*.
#include <cstdint>
#include <span>

#include "combabc/rng/random_stream.hpp"

namespace combabc {

class Simulator {
 public:
  virtual ~Simulator() = default;
  virtual int output_size() const = 0;
  // bits: the full parameter vector (BinarySpace::dimension() entries of 0/1). rng: the
  // candidate's own stream, for stochastic simulators (deterministic ones ignore it).
  // Must be thread-safe. Throwing marks the run failed with the candidate named.
  virtual void Simulate(std::span<const std::uint8_t> bits,
                        RandomStream& rng,
                        std::span<double> out) const = 0;
  // Batch form for simulators that vectorise: n candidates, bits row-major (n x d), out row-major
  // (n x output_size()), rngs[i] for candidate i. The default loops over Simulate.
  virtual void SimulateBatch(std::span<const std::uint8_t> bits,
                             std::span<RandomStream> rngs,
                             std::span<double> out) const;
};

}  // namespace combabc
