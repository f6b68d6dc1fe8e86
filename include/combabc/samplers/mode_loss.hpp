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

// log q(free bits) under a wave's binary proposal: exact and normalised (BinaryProposal::
// LogDensity).
using LogBitsDensity = std::function<double(std::span<const std::uint8_t>)>;

// A class is heavy when its mass reaches both kModeLossMinMass and kModeLossMinParticles particles'
// worth of a wave of n particles, max(0.01, 5 / n), and it is held by at least
// kModeLossMinParticles particles (a single particle with a large importance weight is no mode).
// Many light classes (a posterior spread over many configurations, each held by a particle or two)
// are then never checked: no single one of them is a mode.
inline constexpr double kModeLossMinMass = 0.01;
inline constexpr double kModeLossMinParticles = 5.0;
// A heavy class proposed with less than 1/kModeLossMassRatio of its mass is flagged too: its
// particles would need weights this many times the average, and the product kernels lose a mixed
// run's minor modes this way (tests/samplers/minor_modes_test.cpp: 107-162 where the modes were
// lost, at most 6.3 where they were kept).
inline constexpr double kModeLossMassRatio = 20.0;
double ModeLossMinMass(int particles);

// The pattern classes of `population` (its distinct free-bit patterns, with the sum of their
// particles' normalised weights as mass) whose mass reaches ModeLossMinMass(particles), heaviest
// first (equal masses in pattern order), each with its probability exp(log_q_bits(pattern)) under
// the wave's proposal (at most 1; 0 where the density is NaN). A class is flagged when particles *
// q < 1: a wave of `particles` particles expects fewer than one of the pattern (about particles * q
// of them, as many as the proposal draws it among its candidates if the pattern is accepted about
// as often as the others), where the population held at least 5 particles' worth; or when
// q < mass / kModeLossMassRatio. `bits` are free bits (the caller expands them).
std::vector<PatternClass> FindPatternClasses(const Population& population,
                                             const LogBitsDensity& log_q_bits,
                                             int particles);

}  // namespace combabc
