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
  std::map<std::vector<std::uint8_t>, int> held;  // particles per pattern
  for (std::size_t i = 0; i < population.size; ++i) {
    const auto bits = population.bits_of(i);
    const std::vector<std::uint8_t> key(bits.begin(), bits.end());
    mass[key] += population.weights[i];
    ++held[key];
  }
  const double heavy = ModeLossMinMass(particles);
  std::vector<PatternClass> classes;
  for (const auto& [bits, m] : mass) {
    // A pattern held by fewer than kModeLossMinParticles particles is no mode, however heavy
    // their weights (one importance-weighted particle of 36 bits can carry 2 % of the mass).
    if (m < heavy || held[bits] < static_cast<int>(kModeLossMinParticles)) continue;
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
