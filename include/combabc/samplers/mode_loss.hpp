#pragma once
// The mode-loss diagnostic (docs/algorithm.md, "Mode loss"): which bit patterns carry the mass of
// the population a wave's proposal was fitted to, and whether the proposal still proposes them. A
// kernel that fits the bits poorly (the logistic kernel on a minor pattern whose bits its
// regressions do not capture) can give such a pattern a probability so small that no later wave
// proposes it: the pattern's mode is lost without the ESS noticing, since the ESS sees only the
// particles a wave has.
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "combabc/proposals/proposal.hpp"
#include "combabc/samplers/run_history.hpp"

namespace combabc {

// log(q(free bits, reals) / p(free bits, reals)) under the new wave's joint proposal q and the
// prior p, up to a constant common to the wave (JointProposal::LogDensity minus the prior's).
using LogProposalRatio =
    std::function<double(std::span<const std::uint8_t>, std::span<const double>)>;
// log(q(free bits) / p(free bits)) for the bits alone (JointProposal::LogBitsDensity minus the
// prior's), exact and normalised.
using LogBitsRatio = std::function<double(std::span<const std::uint8_t>)>;

// A class is heavy when its mass reaches both kModeLossMinMass and kModeLossMinParticles particles'
// worth of a wave of n particles, max(0.01, 5 / n), and its particles' effective sample size
// (sum m)^2 / sum m^2 is at least kModeLossMinParticles (a few particles with large importance
// weights are no mode). Many light classes (a posterior spread over many configurations, each
// held by a particle or two) are then never checked as whole patterns: no single one is a mode.
inline constexpr double kModeLossMinMass = 0.01;
inline constexpr double kModeLossMinParticles = 5.0;
// A heavy class given less than 1/kModeLossMassRatio of its mass is flagged too: its particles
// would need weights this many times the average, and the product kernels lose a mixed run's
// minor modes this way (tests/samplers/minor_modes_test.cpp).
inline constexpr double kModeLossMassRatio = 20.0;
// Classes of two bits' values are formed up to this many free bits (4 f (f - 1) / 2 classes, one
// pass over the particles each); classes of one bit's value always.
inline constexpr std::size_t kModeLossMaxPairBits = 64;
// At most this many flagged classes of one or two bits' values are recorded per wave, heaviest
// first (with at most 100 heavy whole patterns: the history's 128 classes a wave).
inline constexpr std::size_t kModeLossMaxPartialClasses = 28;
double ModeLossMinMass(int particles);

// The pattern classes of `population` whose mass reaches ModeLossMinMass(particles), each with its
// share of the new wave (below). The population stands for the posterior the new wave aims at
// through the particles its thresholds still accept (within_next; all when none does or when
// within_next is empty), masses m_i renormalised over them. A class's share is the expected
// fraction of the new wave's accepted particles in it, sum_i m_i q(theta_i) / p(theta_i) over its
// particles, normalised over all; once for the bits alone (log_bits_ratio), once for the bits and
// the reals together (log_ratio), which sees a pattern whose reals the proposal no longer draws.
// Flagged when particles * bits share < 1 (the wave expects fewer than one particle of a class
// that held at least five particles' worth), bits share < mass / kModeLossMassRatio, or
// particles * joint share < 1; `proposal` is the smaller share. First
// every heavy whole free-bit pattern (heaviest first, equal masses in pattern order); then the
// flagged classes of one bit's value (bit a = v: the other entries of `bits` are kAnyBit) and, up
// to kModeLossMaxPairBits free bits, of two bits' values whose bits are not flagged on their own,
// leaving out those that flagged whole patterns hold half of, heaviest first, at most
// kModeLossMaxPartialClasses of them. `bits` are free bits (the caller expands them).
// `log_reweight` (one per particle, or empty) is added to both log ratios: where the weights are
// not the posterior's (the paper estimator's equal weights stand for q_t A, not p A), the
// particles' log p/q_t, so that a share is m_i q / q_t normalised.
std::vector<PatternClass> FindPatternClasses(const Population& population,
                                             const LogProposalRatio& log_ratio,
                                             const LogBitsRatio& log_bits_ratio,
                                             int particles,
                                             std::span<const double> log_reweight = {});

}  // namespace combabc
