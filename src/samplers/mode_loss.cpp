// The mode-loss diagnostic (docs/algorithm.md, "Mode loss").
#include "combabc/samplers/mode_loss.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

namespace combabc {
namespace {

// What the particles of one class add up to: their mass (normalised weights), its square sum
// (for the class's effective sample size) and their shares of the new wave (see below).
struct Tally {
  double mass = 0.0, mass2 = 0.0, bits = 0.0, joint = 0.0;
  void Add(double m, double b, double j) {
    mass += m;
    mass2 += m * m;
    bits += b;
    joint += j;
  }
};

// Shares s_i = m_i exp(log_ratio_i) normalised; 0 for a NaN ratio (a broken density).
std::vector<double> Shares(const std::vector<double>& mass, std::vector<double> log_ratio) {
  double top = -std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < mass.size(); ++k) {
    double& r = log_ratio[k];
    r = std::isnan(r) ? -std::numeric_limits<double>::infinity() : std::log(mass[k]) + r;
    top = std::max(top, r);
  }
  std::vector<double> share(mass.size(), 0.0);
  if (!std::isfinite(top)) return share;
  double sum = 0.0;
  for (std::size_t k = 0; k < mass.size(); ++k) sum += share[k] = std::exp(log_ratio[k] - top);
  for (double& s : share) s /= sum;
  return share;
}

// Heavy: mass >= ModeLossMinMass and an effective sample size of kModeLossMinParticles (a few
// particles of large importance weight are no mode, however many they are).
bool Heavy(const Tally& t, double min_mass) {
  return t.mass >= min_mass && t.mass2 > 0.0 && t.mass * t.mass / t.mass2 >= kModeLossMinParticles;
}

PatternClass ClassOf(std::vector<std::uint8_t> bits, const Tally& t, int particles) {
  PatternClass c;
  c.bits = std::move(bits);
  c.mass = t.mass;
  // Flagged when the bits' share is under one particle or 20 times under the mass (the levels
  // measured on the bits alone), or when the joint share is under one particle: the reals'
  // proposal can starve a class the bits' proposal keeps, but the joint share of a class that
  // survives is often 20 times under its mass too (a mode held by a few heavily weighted
  // particles: tests/samplers/minor_modes_test.cpp), so it gets the first rule only.
  const double n = particles;
  const double by_bits = std::clamp(t.bits, 0.0, 1.0), joint = std::clamp(t.joint, 0.0, 1.0);
  c.proposal = std::min(by_bits, joint);
  c.flagged = n * by_bits < 1.0 || by_bits < c.mass / kModeLossMassRatio || n * joint < 1.0;
  return c;
}

// The mass of the flagged whole patterns within `c` (a class of a few bits' values).
double FlaggedWithin(const PatternClass& c, const std::vector<PatternClass>& whole) {
  double mass = 0.0;
  for (const PatternClass& w : whole) {
    bool inside = w.flagged;
    for (std::size_t k = 0; inside && k < c.bits.size(); ++k) {
      inside = c.bits[k] == kAnyBit || c.bits[k] == w.bits[k];
    }
    mass += inside ? w.mass : 0.0;
  }
  return mass;
}

void SortHeaviestFirst(std::vector<PatternClass>& classes) {
  // Stable: equal masses keep the order they were found in (pattern order, then bit order).
  std::stable_sort(classes.begin(),
                   classes.end(),
                   [](const PatternClass& a, const PatternClass& b) { return a.mass > b.mass; });
}

}  // namespace

double ModeLossMinMass(int particles) {
  return std::max(kModeLossMinMass, kModeLossMinParticles / std::max(1, particles));
}

std::vector<PatternClass> FindPatternClasses(const Population& population,
                                             const LogProposalRatio& log_ratio,
                                             const LogBitsRatio& log_bits_ratio,
                                             int particles,
                                             std::span<const double> log_reweight) {
  const std::size_t f = population.num_free_bits;
  // The particles that stand for the posterior the new wave aims at: those its thresholds still
  // accept (all when none does, or when the caller gave no within_next). A class that the new
  // thresholds leave with little mass is then not heavy, however much it held before: losing it is
  // the schedule's doing, not the proposal's.
  std::vector<std::size_t> kept;
  for (int pass = 0; pass < 2 && kept.empty(); ++pass) {
    for (std::size_t i = 0; i < population.size; ++i) {
      const bool within = pass == 1 || population.within_next.size() != population.size ||
                          population.within_next[i] != 0;
      if (within && population.weights[i] > 0.0) kept.push_back(i);
    }
  }
  if (kept.empty()) return {};
  // Masses m_i (renormalised over the kept particles) and shares s_i: the expected fraction of the
  // new wave's accepted particles near particle i is m_i q(theta_i) / p(theta_i) normalised (the
  // population weighted by m stands for the posterior p A / Z, and the new wave accepts
  // q A / Z'), estimated at the particles themselves: once with the bits' q and p alone, once with
  // bits and reals together. Summed in particle order, so that a resumed run computes the same.
  double total = 0.0;
  for (const std::size_t i : kept) total += population.weights[i];
  std::vector<double> mass(kept.size()), log_joint(kept.size()), log_bits(kept.size());
  for (std::size_t k = 0; k < kept.size(); ++k) {
    const std::size_t i = kept[k];
    mass[k] = population.weights[i] / total;
    const double extra = log_reweight.size() == population.size ? log_reweight[i] : 0.0;
    log_joint[k] = log_ratio(population.bits_of(i), population.reals_of(i)) + extra;
    log_bits[k] = log_bits_ratio(population.bits_of(i)) + extra;
  }
  const std::vector<double> joint = Shares(mass, std::move(log_joint));
  const std::vector<double> share = Shares(mass, std::move(log_bits));
  const double heavy = ModeLossMinMass(particles);

  // Whole patterns: every heavy one is recorded, flagged or not.
  std::map<std::vector<std::uint8_t>, Tally> patterns;
  for (std::size_t k = 0; k < kept.size(); ++k) {
    const auto bits = population.bits_of(kept[k]);
    patterns[std::vector<std::uint8_t>(bits.begin(), bits.end())].Add(mass[k], share[k], joint[k]);
  }
  std::vector<PatternClass> classes;
  for (const auto& [bits, t] : patterns) {
    if (Heavy(t, heavy)) classes.push_back(ClassOf(bits, t, particles));
  }
  SortHeaviestFirst(classes);

  // Classes of one bit's value, and of two bits' values: where every particle's pattern is its own
  // (36 clamps, 500 distinct particles) no whole pattern is heavy, but a clamp's value that holds
  // 5 % of the mass is, and a kernel that stops proposing it loses it just the same. Only flagged
  // ones are recorded (there are 4 f^2 / 2 of them), those of a pair only when neither bit's value
  // is flagged on its own (which says it already).
  std::vector<Tally> single(2 * f);
  for (std::size_t k = 0; k < kept.size(); ++k) {
    const auto bits = population.bits_of(kept[k]);
    for (std::size_t a = 0; a < f; ++a) {
      single[2 * a + (bits[a] ? 1 : 0)].Add(mass[k], share[k], joint[k]);
    }
  }
  std::vector<PatternClass> partial;
  std::vector<std::uint8_t> flagged_value(2 * f, 0);
  for (std::size_t a = 0; a < f; ++a) {
    for (std::uint8_t v = 0; v < 2; ++v) {
      const Tally& t = single[2 * a + v];
      if (!Heavy(t, heavy)) continue;
      std::vector<std::uint8_t> bits(f, kAnyBit);
      bits[a] = v;
      PatternClass c = ClassOf(std::move(bits), t, particles);
      if (!c.flagged) continue;
      flagged_value[2 * a + v] = 1;
      partial.push_back(std::move(c));
    }
  }
  if (f <= kModeLossMaxPairBits) {
    // Tally (a, b) at [(a (f - 1) - a (a - 1) / 2 + b - a - 1) 4 + 2 value_a + value_b], a < b.
    std::vector<Tally> pair(2 * f * (f > 0 ? f - 1 : 0));
    for (std::size_t k = 0; k < kept.size(); ++k) {
      const auto bits = population.bits_of(kept[k]);
      std::size_t at = 0;
      for (std::size_t a = 0; a < f; ++a) {
        for (std::size_t b = a + 1; b < f; ++b, ++at) {
          const std::size_t value = (bits[a] ? 2U : 0U) + (bits[b] ? 1U : 0U);
          pair[4 * at + value].Add(mass[k], share[k], joint[k]);
        }
      }
    }
    std::size_t at = 0;
    for (std::size_t a = 0; a < f; ++a) {
      for (std::size_t b = a + 1; b < f; ++b, ++at) {
        for (std::uint8_t v = 0; v < 4; ++v) {
          const std::uint8_t va = v >> 1, vb = v & 1;
          const Tally& t = pair[4 * at + v];
          if (flagged_value[2 * a + va] || flagged_value[2 * b + vb] || !Heavy(t, heavy)) continue;
          std::vector<std::uint8_t> bits(f, kAnyBit);
          bits[a] = va;
          bits[b] = vb;
          PatternClass c = ClassOf(std::move(bits), t, particles);
          if (c.flagged) partial.push_back(std::move(c));
        }
      }
    }
  }
  // A class most of whose mass is in flagged whole patterns says nothing new (in a few bits, the
  // value of a lost pattern's bit).
  std::erase_if(partial,
                [&](const PatternClass& c) { return FlaggedWithin(c, classes) >= 0.5 * c.mass; });
  SortHeaviestFirst(partial);
  if (partial.size() > kModeLossMaxPartialClasses) partial.resize(kModeLossMaxPartialClasses);
  classes.insert(classes.end(), partial.begin(), partial.end());
  return classes;
}

}  // namespace combabc
