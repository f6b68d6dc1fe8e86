// The mode-loss diagnostic (docs/algorithm.md, "Mode loss").
#include "combabc/samplers/mode_loss.hpp"

#include <algorithm>
#include <cmath>
#include <map>

namespace combabc {

double ModeLossMinMass(int particles) {
  return std::max(kModeLossMinMass, kModeLossMinParticles / std::max(1, particles));
}

std::vector<PatternClass> FindPatternClasses(const Population& population,
                                             const LogBitsDensity& log_q_bits,
                                             int particles) {
  // Masses summed in particle order, so that a resumed run computes the same.
  std::map<std::vector<std::uint8_t>, double> mass;
  for (std::size_t i = 0; i < population.size; ++i) {
    const auto bits = population.bits_of(i);
    mass[std::vector<std::uint8_t>(bits.begin(), bits.end())] += population.weights[i];
  }
  const double heavy = ModeLossMinMass(particles);
  std::vector<PatternClass> classes;
  for (const auto& [bits, m] : mass) {
    if (m < heavy) continue;
    PatternClass c;
    c.bits = bits;
    c.mass = m;
    // A normalised density gives at most 1; a kernel's NaN counts as 0 (flagged), so that what
    // is recorded is always a probability.
    const double q = std::exp(log_q_bits(bits));
    c.proposal = std::isnan(q) ? 0.0 : std::min(q, 1.0);
    c.flagged = static_cast<double>(particles) * c.proposal < 1.0 ||
                c.proposal < c.mass / kModeLossMassRatio;
    classes.push_back(std::move(c));
  }
  // Stable: the map's pattern order among equal masses.
  std::stable_sort(classes.begin(),
                   classes.end(),
                   [](const PatternClass& a, const PatternClass& b) { return a.mass > b.mass; });
  return classes;
}

}  // namespace combabc
