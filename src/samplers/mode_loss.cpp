// The mode-loss diagnostic (docs/algorithm.md, "Mode loss").
#include "combabc/samplers/mode_loss.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
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
    c.proposal = std::exp(log_q_bits(bits));
    c.flagged = static_cast<double>(particles) * c.proposal < 1.0;
    classes.push_back(std::move(c));
  }
  // Stable: the map's pattern order among equal masses.
  std::stable_sort(classes.begin(), classes.end(), [](const PatternClass& a, const PatternClass& b) {
    return a.mass > b.mass;
  });
  return classes;
}

std::string PatternText(const std::vector<std::uint8_t>& bits) {
  constexpr std::size_t kShown = 64;
  std::string text;
  for (std::size_t k = 0; k < std::min(bits.size(), kShown); ++k) text += bits[k] ? '1' : '0';
  if (bits.size() > kShown) {
    const auto set = std::count_if(bits.begin(), bits.end(), [](std::uint8_t b) { return b != 0; });
    text += "... (" + std::to_string(set) + " of " + std::to_string(bits.size()) + " bits set)";
  }
  return text;
}

std::string ModeLossWarning(const WaveRecord& wave) {
  const PatternClass* first = nullptr;
  int more = 0;
  for (const PatternClass& c : wave.pattern_classes) {
    if (!c.flagged) continue;
    if (first == nullptr) {
      first = &c;
    } else {
      ++more;
    }
  }
  if (first == nullptr) return "";
  char numbers[96];
  std::snprintf(numbers,
                sizeof numbers,
                " (mass %.3g) with probability %.2g",
                first->mass,
                first->proposal);
  std::string text = "wave " + std::to_string(wave.wave + 1) + " proposed pattern " +
                     PatternText(first->bits) + numbers;
  if (more > 0) {
    text += " (and " + std::to_string(more) + " more pattern" + (more > 1 ? "s" : "") +
            " likewise)";
  }
  return text + "; the posterior may have lost a mode";
}

}  // namespace combabc
