// Reading a run history back: metadata, waves, the resume point, and truncation for resume.
#include <sqlite3.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>

#include "combabc/core/error.hpp"
#include "combabc/samplers/multi_fidelity.hpp"
#include "history/history_impl.hpp"

namespace combabc {
namespace {

using history::Statement;

// Columns of Impl::WaveSelect(), in history::kWaveColumns order.
enum WaveColumn {
  kWave,
  kThresholds,
  kPhi,
  kProposal,
  kStartedAt,
  kAcceptedNeeded,
  kNextIndex,
  kAcceptedSoFar,
  kTotalSimulations,
  kEnded,
  kComplete,
  kCandidates,
  kAccepted,
  kAcceptanceRate,
  kMarginalsPaper,
  kMarginalsImportance,
  kEss,
  kDistinct,
  kWallSeconds,
  kEndedAt,
  kDiscarded,
  kContentHash,
  kRealsMean,
  kRealsSd,
  kFailures,
  kContinueIfAccepted,
  kContinueIfRejected,
  kExpensiveSimulations,
  kCheapSeconds,
  kExpensiveSeconds,
  kUnkeptFalsePositives,
  kUnkeptFalsePositiveLogW2,
  kNextContinueIfAccepted,
  kNextContinueIfRejected,
  kCostRatio,
  kPatternBits,
  kPatternMass,
  kPatternProposal,
  kPatternFlagged,
  kMoveSurvivorEss,
  kMoveStep,
  kMoveRounds,
  kMoveProposed,
  kMoveAccepted,
  kMoveIndependentProposed,
  kMoveIndependentAccepted,
};

// Columns of history::kParticleColumns.
enum ParticleColumn {
  kCandidate,
  kBits,
  kLogWeight,
  kWeight,
  kDistance,
  kOutput,
  kReals,
  kMultiplier,
  kConfirmed,
  kLowDistance,
  kAncestor,
};

// Reads one wave's fields, each checked against what the run's metadata say it must measure.
// Errors name the file, the wave (numbered from 1, as users see it) and the field.
class WaveReader {
 public:
  WaveReader(const std::string& path, int wave) : path_(path), wave_(wave) {}

  [[noreturn]] void Corrupt(const std::string& field, const std::string& what) const {
    throw Error(ErrorKind::kData,
                "corrupt run history: " + what,
                path_,
                0,
                "wave " + std::to_string(wave_ + 1) + ", " + field);
  }

  static constexpr std::int64_t kMaxCount = std::int64_t{1} << 40;
  std::int64_t Count(const Statement& row, int column, const char* field) const {
    if (row.IsNull(column)) Corrupt(field, "is NULL");
    // SQLite converts a REAL (9.3e18, Inf) to the nearest int64 on read: only a stored integer is
    // a count, and no wave gets near 2^40 (10^12) simulations, so larger values are damage.
    if (row.Type(column) != SQLITE_INTEGER) Corrupt(field, "is not an integer");
    const std::int64_t value = row.Int(column);
    if (value < 0) Corrupt(field, "is negative (" + std::to_string(value) + ")");
    if (value > kMaxCount) Corrupt(field, "is implausibly large (" + std::to_string(value) + ")");
    return value;
  }

  // A finite number that `valid` accepts (NULL is corrupt); `expected` says what it must be.
  template <typename Valid>
  double Real(const Statement& row,
              int column,
              const char* field,
              Valid valid,
              const char* expected) const {
    if (row.IsNull(column)) Corrupt(field, "is NULL");
    const int type = row.Type(column);
    const double value = row.Real(column);
    if ((type != SQLITE_FLOAT && type != SQLITE_INTEGER) || !std::isfinite(value) ||
        !valid(value)) {
      Corrupt(field, "is '" + row.Text(column) + "', not " + expected);
    }
    return value;
  }

  // A vector of doubles of `min` to `max` values; NULL is the empty vector.
  std::vector<double> Doubles(const Statement& row,
                              int column,
                              std::size_t min,
                              std::size_t max,
                              const std::string& field,
                              const std::string& expected) const {
    const int type = row.Type(column);
    if (type != SQLITE_BLOB && type != SQLITE_NULL) Corrupt(field, "is not a BLOB of doubles");
    const auto bytes = row.Bytes(column);
    if (bytes.size() % sizeof(double) != 0) {
      Corrupt(field,
              "has " + std::to_string(bytes.size()) + " bytes, not a whole number of doubles");
    }
    const std::size_t n = bytes.size() / sizeof(double);
    if (n < min || n > max) {
      Corrupt(field,
              (n == 0 ? std::string("is NULL") : "has " + std::to_string(n) + " values") +
                  ", expected " + expected);
    }
    return history::UnpackDoubles(std::vector<std::uint8_t>(bytes.begin(), bytes.end()), path_);
  }

  std::vector<std::uint8_t> Bits(const Statement& row,
                                 int column,
                                 int dimension,
                                 const std::string& field) const {
    const auto bytes = row.Bytes(column);
    const auto needed = (static_cast<std::size_t>(dimension) + 7) / 8;
    if (row.Type(column) != SQLITE_BLOB || bytes.size() != needed) {
      Corrupt(field,
              (row.IsNull(column) ? std::string("is NULL")
                                  : "has " + std::to_string(bytes.size()) + " bytes") +
                  ", expected " + std::to_string(needed) + " (" + std::to_string(dimension) +
                  " bits)");
    }
    return history::UnpackBits(
        std::vector<std::uint8_t>(bytes.begin(), bytes.end()), dimension, path_);
  }

 private:
  const std::string& path_;
  int wave_;
};

bool IsProbability(double value) { return value > 0.0 && value <= 1.0; }
bool IsNonNegative(double value) { return value >= 0.0; }

// A wave's multi-fidelity columns (schema v7): nullopt when they are NULL (a single-fidelity run).
// Its next_* and cost_ratio are recorded when the wave ends; a wave not ended keeps the defaults.
std::optional<WaveFidelity> ReadFidelity(const WaveReader& check,
                                         const Statement& row,
                                         std::int64_t candidates,
                                         bool ended) {
  if (row.IsNull(kContinueIfAccepted)) {
    for (int c = kContinueIfRejected; c <= kCostRatio; ++c) {
      if (!row.IsNull(c)) {
        check.Corrupt("continue_if_accepted",
                      "is NULL, but the wave's other multi-fidelity columns are not");
      }
    }
    return std::nullopt;
  }
  constexpr const char* kProbability = "a probability in (0, 1]";
  constexpr const char* kSeconds = "a number of seconds >= 0";
  WaveFidelity f;
  f.continue_if_accepted =
      check.Real(row, kContinueIfAccepted, "continue_if_accepted", IsProbability, kProbability);
  f.continue_if_rejected =
      check.Real(row, kContinueIfRejected, "continue_if_rejected", IsProbability, kProbability);
  f.expensive_simulations = check.Count(row, kExpensiveSimulations, "expensive_simulations");
  if (f.expensive_simulations > candidates) {
    check.Corrupt("expensive_simulations",
                  "counts " + std::to_string(f.expensive_simulations) +
                      " expensive simulations, more than the wave's " + std::to_string(candidates) +
                      " candidates");
  }
  f.cheap_seconds = check.Real(row, kCheapSeconds, "cheap_seconds", IsNonNegative, kSeconds);
  f.expensive_seconds =
      check.Real(row, kExpensiveSeconds, "expensive_seconds", IsNonNegative, kSeconds);
  f.unkept_false_positives = check.Count(row, kUnkeptFalsePositives, "unkept_false_positives");
  if (f.unkept_false_positives > f.expensive_simulations) {
    check.Corrupt("unkept_false_positives",
                  "counts " + std::to_string(f.unkept_false_positives) +
                      " false positives, more than the wave's " +
                      std::to_string(f.expensive_simulations) + " expensive simulations");
  }
  // log sum of squared weights: -inf exactly when there is none.
  const int type =
      row.IsNull(kUnkeptFalsePositiveLogW2) ? SQLITE_NULL : row.Type(kUnkeptFalsePositiveLogW2);
  f.unkept_false_positive_log_w2 = type == SQLITE_NULL ? 0.0 : row.Real(kUnkeptFalsePositiveLogW2);
  const bool none = f.unkept_false_positives == 0;
  if ((type != SQLITE_FLOAT && type != SQLITE_INTEGER) ||
      none != (f.unkept_false_positive_log_w2 == -std::numeric_limits<double>::infinity()) ||
      std::isnan(f.unkept_false_positive_log_w2) ||
      f.unkept_false_positive_log_w2 == std::numeric_limits<double>::infinity()) {
    check.Corrupt("unkept_false_positive_log_w2",
                  "is '" + row.Text(kUnkeptFalsePositiveLogW2) +
                      "', not -Inf for no false positive or a finite log sum for some");
  }
  if (ended && !row.IsNull(kNextContinueIfAccepted)) {
    f.next_continue_if_accepted = check.Real(
        row, kNextContinueIfAccepted, "next_continue_if_accepted", IsProbability, kProbability);
    f.next_continue_if_rejected = check.Real(
        row, kNextContinueIfRejected, "next_continue_if_rejected", IsProbability, kProbability);
    f.cost_ratio =
        check.Real(row, kCostRatio, "cost_ratio", IsNonNegative, "a cost ratio >= 0 (0: measured)");
  }
  return f;
}

// A particle's multi-fidelity columns: all NULL in a single-fidelity wave; in a multi-fidelity one
// its cheap distance (one value per component), whether it was confirmed, and a multiplier that
// MultiFidelityMultiplier gives under the wave's continuation probabilities: 1 unconfirmed, else
// 1 (both accepted), 1 - 1/eta_1 (the expensive model rejected a cheap acceptance) or 1/eta_2
// (it accepted a cheap rejection).
void ReadParticleFidelity(const WaveReader& check,
                          const Statement& row,
                          const std::optional<WaveFidelity>& fidelity,
                          const std::string& who,
                          std::size_t components,
                          Particle& p) {
  if (!fidelity) {
    if (!row.IsNull(kMultiplier) || !row.IsNull(kConfirmed) || !row.IsNull(kLowDistance)) {
      check.Corrupt(who + " multiplier",
                    "has multi-fidelity columns in a wave without continuation probabilities");
    }
    return;
  }
  const std::string per_component = std::to_string(components) + " (one per distance component)";
  p.low_distance = check.Doubles(
      row, kLowDistance, components, components, who + " low_distance", per_component);
  if (row.Type(kConfirmed) != SQLITE_INTEGER ||
      (row.Int(kConfirmed) != 0 && row.Int(kConfirmed) != 1)) {
    check.Corrupt(who + " confirmed", "is '" + row.Text(kConfirmed) + "', not 0 or 1");
  }
  p.confirmed = row.Int(kConfirmed) != 0;
  const std::string field = who + " multiplier";
  p.multiplier = check.Real(
      row, kMultiplier, field.c_str(), [](double) { return true; }, "a finite number");
  MultiFidelityOptions etas;
  etas.continue_if_accepted = fidelity->continue_if_accepted;
  etas.continue_if_rejected = fidelity->continue_if_rejected;
  const bool consistent =
      p.confirmed ? p.multiplier == MultiFidelityMultiplier(etas, true, true, true) ||
                        p.multiplier == MultiFidelityMultiplier(etas, true, true, false) ||
                        p.multiplier == MultiFidelityMultiplier(etas, false, true, true)
                  : p.multiplier == 1.0;
  if (!consistent || p.multiplier == 0.0) {
    check.Corrupt(field,
                  "is " + row.Text(kMultiplier) + ", which no " +
                      (p.confirmed ? "confirmed" : "unconfirmed") +
                      " particle has under the wave's continuation probabilities");
  }
}

// The wave's pattern classes (schema v8; NULL columns: none): pattern_mass and pattern_proposal
// one double per class, pattern_bits each class's packed bits in turn (from v9, where a class of
// one or two bits' values is among them: each class's bits, then its mask), pattern_flagged a byte
// 0/1 per class.
std::vector<PatternClass> ReadPatternClasses(const WaveReader& check,
                                             const Statement& row,
                                             int dimension,
                                             bool masks,
                                             const std::string& path) {
  // Each class holds at least 1 % of a mass of 1 (ModeLossMinMass): at most 100, and rounding.
  constexpr std::size_t kMaxClasses = 128;
  const auto mass =
      check.Doubles(row, kPatternMass, 0, kMaxClasses, "pattern_mass", "at most 128 classes");
  const std::size_t k = mass.size();
  const std::string per_class = std::to_string(k) + " (one per class of pattern_mass)";
  const auto proposal = check.Doubles(row, kPatternProposal, k, k, "pattern_proposal", per_class);
  const auto bytes_per_class = (static_cast<std::size_t>(dimension) + 7) / 8;
  const auto bits = row.Bytes(kPatternBits);
  const auto flagged = row.Bytes(kPatternFlagged);
  const bool masked = masks && k > 0 && bits.size() == 2 * k * bytes_per_class;
  const std::size_t stride = (masked ? 2 : 1) * bytes_per_class;
  if (bits.size() != k * stride || (k > 0 && row.Type(kPatternBits) != SQLITE_BLOB)) {
    check.Corrupt("pattern_bits",
                  "has " + std::to_string(bits.size()) + " bytes, expected " +
                      std::to_string(k * bytes_per_class) + " (" + per_class + ")");
  }
  if (flagged.size() != k || (k > 0 && row.Type(kPatternFlagged) != SQLITE_BLOB)) {
    check.Corrupt("pattern_flagged",
                  "has " + std::to_string(flagged.size()) + " bytes, expected " + per_class);
  }
  std::vector<PatternClass> classes(k);
  for (std::size_t c = 0; c < k; ++c) {
    const std::string who = "pattern class " + std::to_string(c + 1);
    if (!(mass[c] > 0.0 && mass[c] <= 1.0 + 1e-9) || !(proposal[c] >= 0.0 && proposal[c] <= 1.0) ||
        flagged[c] > 1) {
      check.Corrupt(who, "has mass, proposal or flag out of range");
    }
    const auto* first = bits.data() + c * stride;
    classes[c].bits = history::UnpackBits(
        std::vector<std::uint8_t>(first, first + bytes_per_class), dimension, path);
    if (masked) {
      const auto fixed = history::UnpackBits(
          std::vector<std::uint8_t>(first + bytes_per_class, first + stride), dimension, path);
      for (std::size_t b = 0; b < fixed.size(); ++b) {
        if (fixed[b] == 0 && classes[c].bits[b] != 0) {
          check.Corrupt(who, "has a bit set that its mask leaves free");
        }
        if (fixed[b] == 0) classes[c].bits[b] = kAnyBit;
      }
    }
    classes[c].mass = mass[c];
    classes[c].proposal = proposal[c];
    classes[c].flagged = flagged[c] != 0;
  }
  return classes;
}

// A resample-move wave's move statistics (schema v10): nullopt when every column is NULL (a
// rejection wave). The counts must nest: accepted and independent proposals within the proposals,
// independent acceptances within both.
std::optional<WaveMoves> ReadMoves(const WaveReader& check, const Statement& row) {
  static constexpr const char* kNames[] = {"move_survivor_ess",
                                           "move_step",
                                           "move_rounds",
                                           "move_proposed",
                                           "move_accepted",
                                           "move_independent_proposed",
                                           "move_independent_accepted"};
  int nulls = 0;
  const char* null = nullptr;
  for (int c = kMoveSurvivorEss; c <= kMoveIndependentAccepted; ++c) {
    if (row.IsNull(c)) {
      ++nulls;
      null = null ? null : kNames[c - kMoveSurvivorEss];
    }
  }
  if (nulls == kMoveIndependentAccepted - kMoveSurvivorEss + 1) return std::nullopt;
  if (null) check.Corrupt(null, "is NULL where the wave's other move columns are not");
  WaveMoves m;
  m.survivor_ess = check.Real(
      row, kMoveSurvivorEss, "move_survivor_ess", IsNonNegative, "an effective sample size >= 0");
  m.step = check.Real(
      row,
      kMoveStep,
      "move_step",
      [](double value) { return value >= 0.0 && value <= 1.0; },
      "a fraction of the schedule's step in [0, 1]");
  const std::int64_t rounds = check.Count(row, kMoveRounds, "move_rounds");
  // MoveOptions::max_rounds is at most 10000.
  if (rounds > 10000) check.Corrupt("move_rounds", "is " + std::to_string(rounds) + ", over 10000");
  m.rounds = static_cast<int>(rounds);
  m.proposed = check.Count(row, kMoveProposed, "move_proposed");
  m.accepted = check.Count(row, kMoveAccepted, "move_accepted");
  m.independent_proposed = check.Count(row, kMoveIndependentProposed, "move_independent_proposed");
  m.independent_accepted = check.Count(row, kMoveIndependentAccepted, "move_independent_accepted");
  auto within = [&](std::int64_t part, std::int64_t whole, const char* field, const char* of) {
    if (part > whole) {
      check.Corrupt(
          field,
          "counts " + std::to_string(part) + ", more than the " + std::to_string(whole) + " " + of);
    }
  };
  within(m.accepted, m.proposed, "move_accepted", "proposals");
  within(m.independent_proposed, m.proposed, "move_independent_proposed", "proposals");
  within(m.independent_accepted,
         m.independent_proposed,
         "move_independent_accepted",
         "independent proposals");
  within(m.independent_accepted, m.accepted, "move_independent_accepted", "accepted proposals");
  return m;
}

// The wave row's counts and summaries: all of them for a wave that ended, its progress only for
// one cut short before OnWaveEnd (LoadHistory derives the rest from the particles).
void ReadWaveCounts(const WaveReader& check,
                    const Statement& row,
                    const HistoryShape& shape,
                    bool ended,
                    std::int64_t next_index,
                    WaveRecord& wave) {
  const auto d = static_cast<std::size_t>(shape.dimension);
  if (ended) {
    wave.complete = row.Int(kComplete) != 0;
    wave.candidates = check.Count(row, kCandidates, "candidates");
    wave.accepted = check.Count(row, kAccepted, "accepted");
    wave.acceptance_rate = row.Real(kAcceptanceRate);
    // A wave that accepted nothing has no marginals.
    const std::size_t min = wave.accepted == 0 ? 0 : d;
    const std::string per_bit = std::to_string(d) + " (one per bit)";
    wave.marginals_paper = check.Doubles(row, kMarginalsPaper, min, d, "marginals_paper", per_bit);
    wave.marginals_importance =
        check.Doubles(row, kMarginalsImportance, min, d, "marginals_importance", per_bit);
    wave.ess = row.Real(kEss);
    wave.distinct = check.Count(row, kDistinct, "distinct_count");
    wave.wall_seconds = row.Real(kWallSeconds);
    const std::size_t r = shape.reals;
    const std::size_t min_reals = wave.accepted == 0 ? 0 : r;
    const std::string per_real = std::to_string(r) + " (one per real parameter)";
    wave.reals_mean = check.Doubles(row, kRealsMean, min_reals, r, "reals_mean", per_real);
    wave.reals_sd = check.Doubles(row, kRealsSd, min_reals, r, "reals_sd", per_real);
  } else {
    // A wave cut short before OnWaveEnd: only its progress is known (LoadHistory derives the
    // rest from the particles).
    wave.candidates = next_index;
    wave.accepted = check.Count(row, kAcceptedSoFar, "accepted_so_far");
    wave.acceptance_rate = wave.candidates > 0 ? static_cast<double>(wave.accepted) /
                                                     static_cast<double>(wave.candidates)
                                               : 0.0;
  }
}

// One particle row, every vector checked against the shape: its index one of the wave's
// `indices`, its ancestor (when stored) one of the previous wave's `ancestors`.
Particle ReadParticle(const WaveReader& check,
                      const Statement& particles,
                      const HistoryShape& shape,
                      const std::optional<WaveFidelity>& fidelity,
                      std::int64_t indices,
                      std::int64_t ancestors) {
  const std::string distance_count =
      std::to_string(shape.components) + " (one per distance component)";
  const std::string output_count =
      "0 or " + std::to_string(shape.outputs) + " (one per output position)";
  Particle p;
  p.index = particles.Int(kCandidate);
  const std::string who = "particle " + std::to_string(p.index);
  if (p.index < 0 || p.index >= indices) {
    check.Corrupt(who, "lies outside the wave's " + std::to_string(indices) + " candidates");
  }
  p.theta.bits = check.Bits(particles, kBits, shape.dimension, who + " bits");
  p.log_weight = particles.Real(kLogWeight);
  p.weight = particles.Real(kWeight);
  p.distance = check.Doubles(
      particles, kDistance, shape.components, shape.components, who + " distance", distance_count);
  p.output = check.Doubles(particles, kOutput, 0, shape.outputs, who + " output", output_count);
  if (!p.output.empty() && p.output.size() != shape.outputs) {
    check.Corrupt(who + " output",
                  "has " + std::to_string(p.output.size()) + " values, expected " + output_count);
  }
  p.theta.reals = check.Doubles(particles,
                                kReals,
                                shape.reals,
                                shape.reals,
                                who + " reals",
                                std::to_string(shape.reals) + " (one per real parameter)");
  for (std::size_t i = 0; i < p.theta.reals.size(); ++i) {
    // A particle's reals were drawn inside their prior's support: never NaN or infinite.
    if (!std::isfinite(p.theta.reals[i])) {
      check.Corrupt(who + " reals", "value " + std::to_string(i + 1) + " is not finite");
    }
  }
  ReadParticleFidelity(check, particles, fidelity, who, shape.components, p);
  if (!particles.IsNull(kAncestor)) {
    const std::string field = who + " ancestor";
    p.ancestor = check.Count(particles, kAncestor, field.c_str());
    if (p.ancestor >= ancestors) {
      check.Corrupt(field,
                    "is " + std::to_string(p.ancestor) + ", not one of the previous wave's " +
                        std::to_string(ancestors) + " particle numbers");
    }
  }
  return p;
}

}  // namespace

std::string HistoryStore::Impl::WaveSelect() const {
  std::string columns = history::kWaveColumns;
  // Before version 10 every wave was a rejection wave: its move columns are NULL.
  const std::size_t moves = columns.find(", move_survivor_ess");
  const std::string moves_tail =
      has_moves() ? columns.substr(moves) : ", NULL, NULL, NULL, NULL, NULL, NULL, NULL";
  columns.erase(moves);
  // Before version 8 no wave recorded pattern classes: its columns are NULL (none).
  const std::size_t patterns = columns.find(", pattern_bits");
  const std::string pattern_tail =
      has_pattern_classes() ? columns.substr(patterns) : ", NULL, NULL, NULL, NULL";
  columns.erase(patterns);
  // Before version 7 no run had a low-fidelity simulator: its multi-fidelity columns are NULL.
  const std::size_t fidelity = columns.find(", continue_if_accepted");
  const std::string tail = has_multi_fidelity()
                               ? columns.substr(fidelity)
                               : ", NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL";
  columns.erase(fidelity);
  if (!checksummed()) {
    // Version 1 had neither column: no overshoot recorded, no checksum; nor any reals.
    columns.replace(
        columns.find("discarded, content_hash"), std::string::npos, "0, NULL, NULL, NULL, 0");
  } else if (!has_reals()) {
    columns.replace(columns.find("reals_mean, reals_sd"), std::string::npos, "NULL, NULL, 0");
  } else if (!has_failures()) {
    columns.replace(columns.rfind("failures"), std::string::npos, "0");  // none recorded
  }
  return "SELECT " + columns + tail + pattern_tail + moves_tail + " FROM wave";
}

std::string HistoryStore::Impl::ParticleSelect() const {
  std::string columns = history::kParticleColumns;
  // Before version 10 every particle was drawn afresh (no ancestor), before version 7 a particle
  // had no multi-fidelity columns, and before version 3 no reals.
  if (!has_moves()) columns.replace(columns.rfind("ancestor"), std::string::npos, "NULL");
  if (!has_multi_fidelity()) {
    columns.replace(columns.find("multiplier"), std::string::npos, "NULL, NULL, NULL, NULL");
  }
  if (!has_reals()) columns.replace(columns.find("reals"), 5, "NULL");
  return "SELECT " + columns + " FROM particle";
}

std::optional<HistoryStore::Impl::PartialWave> HistoryStore::Impl::FindPartial() {
  Statement s(db, "SELECT wave, next_index, ended, complete FROM wave ORDER BY wave");
  while (s.Step()) {
    if (s.Int(2) != 0 && s.Int(3) != 0) continue;
    PartialWave partial{static_cast<int>(s.Int(0)), s.Int(1), s.Int(2) != 0};
    s.Reset();
    return partial;
  }
  return std::nullopt;
}

WaveRecord HistoryStore::Impl::ReadWave(Statement& row, int expected_wave) {
  const WaveReader check(db.path(), expected_wave);
  if (row.Type(kWave) != SQLITE_INTEGER || row.Int(kWave) != expected_wave) {
    check.Corrupt("wave",
                  "waves are not numbered 1, 2, 3, ... (found " + row.Text(kWave) + " where wave " +
                      std::to_string(expected_wave) + " was due, 0-based)");
  }
  const auto d = static_cast<std::size_t>(shape.dimension);
  const std::size_t k = shape.threshold_components;
  WaveRecord wave;
  wave.wave = expected_wave;
  wave.thresholds = check.Doubles(
      row, kThresholds, k, k, "thresholds", std::to_string(k) + " (one per threshold component)");
  wave.phi = row.Real(kPhi);
  if (expected_wave == 0) shape.free_parameters = 0;
  const std::size_t f = shape.free_parameters;
  // A continuous-only run (d = 0) has no binary proposal.
  wave.proposal = f == 0
                      ? check.Doubles(row,
                                      kProposal,
                                      std::min<std::size_t>(1, d),
                                      d,
                                      "proposal",
                                      "1 to " + std::to_string(d) + " (one per free parameter)")
                      : check.Doubles(row,
                                      kProposal,
                                      f,
                                      f,
                                      "proposal",
                                      std::to_string(f) + " (one per free parameter, as wave 1)");
  shape.free_parameters = wave.proposal.size();
  const std::int64_t next_index = check.Count(row, kNextIndex, "next_index");
  wave.discarded = check.Count(row, kDiscarded, "discarded");
  const bool ended = row.Int(kEnded) != 0;
  ReadWaveCounts(check, row, shape, ended, next_index, wave);

  wave.multi_fidelity = ReadFidelity(check, row, wave.candidates, ended);
  wave.pattern_classes =
      ReadPatternClasses(check, row, shape.dimension, has_pattern_masks(), db.path());
  wave.moves = ReadMoves(check, row);
  // A move wave's particles are numbered by their slot (0 .. n-1), not by a candidate: one whose
  // proposals fell outside the prior (not simulated) may have fewer candidates than particles.
  const std::int64_t indices =
      wave.moves ? std::max(wave.candidates, wave.accepted) : wave.candidates;
  // A particle's ancestor is one of the previous wave's particles (none before wave 1).
  const std::int64_t ancestors = expected_wave == 0 ? 0 : shape.previous_candidates;
  shape.previous_candidates = indices;

  Statement particles(db, (ParticleSelect() + " WHERE wave = ?1 ORDER BY candidate").c_str());
  particles.Bind(1, expected_wave);
  history::WaveHasher hasher(schema_version);
  std::int64_t confirmed = 0;
  while (particles.Step()) {
    hasher.AddParticle(particles);
    Particle p = ReadParticle(check, particles, shape, wave.multi_fidelity, indices, ancestors);
    confirmed += p.confirmed ? 1 : 0;
    wave.particles.push_back(std::move(p));
  }
  // Each confirmed particle ran the expensive simulator.
  if (wave.multi_fidelity && confirmed > wave.multi_fidelity->expensive_simulations) {
    check.Corrupt("expensive_simulations",
                  "counts " + std::to_string(wave.multi_fidelity->expensive_simulations) +
                      " expensive simulations, fewer than the wave's " + std::to_string(confirmed) +
                      " confirmed particles");
  }
  // Not stored: recomputed from the stored bits and weights as the run computed them, so a loaded
  // wave's equal the run's.
  wave.pair_correlations = PairCorrelations(wave.particles);
  const std::int64_t failures = check.Count(row, kFailures, "failures");
  if (has_failures()) {
    Statement rows(db,
                   (std::string("SELECT ") + history::kFailureColumns +
                    " FROM failure WHERE wave = ?1 ORDER BY candidate")
                       .c_str());
    rows.Bind(1, expected_wave);
    while (rows.Step()) {
      hasher.AddFailure(rows);
      SimulationFailure failure;
      failure.index = rows.Int(0);
      failure.reason = rows.Text(1);
      if (failure.index < 0 || failure.index >= wave.candidates) {
        check.Corrupt("failure " + std::to_string(failure.index),
                      "lies outside the wave's " + std::to_string(wave.candidates) + " candidates");
      }
      wave.failures.push_back(std::move(failure));
    }
  }
  if (static_cast<std::int64_t>(wave.failures.size()) != failures) {
    check.Corrupt("failures",
                  "counts " + std::to_string(failures) + " failed simulations, the table holds " +
                      std::to_string(wave.failures.size()));
  }
  if (checksummed()) {
    const auto stored = history::ParseHexDigest(row.Text(kContentHash));
    if (!stored) check.Corrupt("content_hash", "the wave's checksum is missing or malformed");
    if (*stored != hasher.Finish(row)) {
      check.Corrupt("content_hash", "the wave's rows and particles do not match its checksum");
    }
  }
  return wave;
}

RunMetadata HistoryStore::LoadMetadata() const {
  history::Database& db = impl_->db;
  history::ReadSnapshot snapshot(db);
  RunMetadata m;
  Statement run(db, R"sql(
    SELECT status, config_text, config_path, combabc_version, git_hash, seed, threads,
      start_time, end_time, termination, message, resume_count, estimator, dimension,
      position_unit FROM run WHERE id = 1)sql");
  if (!run.Step()) throw Error(ErrorKind::kData, "corrupt run history: no run row", db.path());
  const std::string status = run.Text(0);
  const std::optional<RunStatus> parsed = ParseEnum<RunStatus>(status);
  if (!parsed) {
    throw Error(
        ErrorKind::kData, "corrupt run history: unknown status '" + status + "'", db.path());
  }
  m.status = *parsed;
  m.config_text = run.Text(1);
  m.config_path = run.Text(2);
  m.combabc_version = run.Text(3);
  m.git_hash = run.Text(4);
  m.seed = std::strtoull(run.Text(5).c_str(), nullptr, 10);
  m.threads = static_cast<int>(run.Int(6));
  m.start_time = run.Text(7);
  m.end_time = run.Text(8);
  m.termination = run.Text(9);
  m.summary_message = run.Text(10);
  m.resume_count = static_cast<int>(run.Int(11));
  m.estimator = run.Text(12);
  m.dimension = static_cast<int>(run.Int(13));
  m.position_unit = run.Text(14);
  run.Reset();

  Statement bits(db, "SELECT name, prior FROM bit ORDER BY bit");
  while (bits.Step()) {
    m.bit_names.push_back(bits.Text(0));
    m.bit_prior_one.push_back(bits.Real(1));
  }
  Statement components(db, "SELECT name, kind, required FROM component ORDER BY component");
  while (components.Step()) {
    DistanceComponent c;
    c.name = components.Text(0);
    c.kind = ParseEnum<ComponentKind>(components.Text(1)).value_or(ComponentKind::kThreshold);
    c.required = components.Real(2);
    m.distance_components.push_back(c);
  }
  Statement positions(db, "SELECT position FROM output_position ORDER BY i");
  while (positions.Step()) m.output_positions.push_back(positions.Real(0));
  Statement measured(db, "SELECT position, value FROM measured ORDER BY i");
  while (measured.Step()) {
    m.measured.positions.push_back(measured.Real(0));
    m.measured.values.push_back(measured.Real(1));
  }
  m.schema_version = static_cast<int>(db.QueryInt("PRAGMA user_version"));
  if (m.schema_version >= 6) {
    Statement experiments(db, R"sql(
      SELECT name, description, outputs, measured, components FROM experiment ORDER BY e)sql");
    while (experiments.Step()) {
      StoredExperiment x;
      x.name = experiments.Text(0);
      x.description = experiments.Text(1);
      x.outputs = static_cast<int>(experiments.Int(2));
      x.measured = static_cast<int>(experiments.Int(3));
      x.components = static_cast<int>(experiments.Int(4));
      m.experiments.push_back(std::move(x));
    }
  } else {
    // Before v6 a run had one experiment, unnamed, holding every output, point and component.
    StoredExperiment x;
    x.outputs = static_cast<int>(m.output_positions.size());
    x.measured = static_cast<int>(m.measured.positions.size());
    x.components = static_cast<int>(m.distance_components.size());
    m.experiments.push_back(std::move(x));
  }
  Statement limits(
      db, "SELECT key, value FROM meta WHERE substr(key, 1, 11) = 'stop_limit_' ORDER BY key");
  while (limits.Step()) m.stop_limits.emplace_back(limits.Text(0).substr(11), limits.Text(1));
  // A history from before the proposal table ran the default kernels of the time: independent (the
  // default is now kAuto, which is resolved before it is recorded).
  m.proposal.binary = BinaryKernelKind::kIndependent;
  if (m.schema_version < 3) return m;  // no reals, default kernels, no fingerprint
  Statement reals(db, "SELECT name, kind, low, high, mean, sd FROM real ORDER BY i");
  while (reals.Step()) {
    ContinuousParameter parameter;
    parameter.name = reals.Text(0);
    parameter.prior.kind = ParseEnum<PriorKind>(reals.Text(1)).value_or(PriorKind::kUniform);
    parameter.prior.low = reals.Real(2);
    parameter.prior.high = reals.Real(3);
    parameter.prior.mean = reals.Real(4);
    parameter.prior.sd = reals.Real(5);
    m.reals.push_back(std::move(parameter));
  }
  Statement proposal(db, R"sql(
    SELECT binary_kernel, min_correlation, max_predecessors, ridge, min_marginal, clip,
      continuous_kernel, scale, tempering_form FROM proposal WHERE id = 1)sql");
  if (proposal.Step()) {
    ProposalOptions& p = m.proposal;
    p.binary = ParseEnum<BinaryKernelKind>(proposal.Text(0)).value_or(p.binary);
    p.logistic.min_correlation = proposal.Real(1);
    p.logistic.max_predecessors = static_cast<int>(proposal.Int(2));
    p.logistic.ridge = proposal.Real(3);
    p.logistic.min_marginal = proposal.Real(4);
    p.logistic.clip = proposal.Real(5);
    p.continuous = ParseEnum<ContinuousKernelKind>(proposal.Text(6)).value_or(p.continuous);
    p.scale = proposal.Real(7);
    m.tempering_form = proposal.Text(8);
    proposal.Reset();
  }
  Statement fingerprint(db, R"sql(
    SELECT substr(key, 13), value FROM meta WHERE substr(key, 1, 12) = 'fingerprint_'
    ORDER BY key)sql");
  while (fingerprint.Step()) m.fingerprint.emplace_back(fingerprint.Text(0), fingerprint.Text(1));
  return m;
}

ResumePoint HistoryStore::LoadResumePoint() const {
  Impl& impl = *impl_;
  history::ReadSnapshot snapshot(impl.db);
  ResumePoint point;
  Statement rows(impl.db, (impl.WaveSelect() + " ORDER BY wave").c_str());
  while (rows.Step()) {
    const bool ended = rows.Int(kEnded) != 0;
    const bool complete = rows.Int(kComplete) != 0;
    const int expected = static_cast<int>(point.completed.size());
    if (ended && complete) {
      point.completed.push_back(impl.ReadWave(rows, expected));
      continue;
    }
    // The first incomplete wave is where the run continues; nothing after it counts. A wave
    // started without any committed batch is simply started again.
    if (rows.Int(kNextIndex) > 0) {
      WaveRecord partial = impl.ReadWave(rows, expected);
      point.has_partial = true;
      point.partial_wave = expected;
      point.partial_next_index = rows.Int(kNextIndex);
      point.partial_accepted = std::move(partial.particles);
      point.partial_discarded = partial.discarded;
      point.partial_failures = std::move(partial.failures);
      point.partial_fidelity = partial.multi_fidelity;
    }
    rows.Reset();
    break;
  }
  return point;
}

RunHistory HistoryStore::LoadHistory() const {
  Impl& impl = *impl_;
  history::ReadSnapshot snapshot(impl.db);
  RunHistory history;
  Statement rows(impl.db, (impl.WaveSelect() + " ORDER BY wave").c_str());
  std::int64_t simulations = 0;
  std::int64_t discarded = 0;
  while (rows.Step()) {
    const bool ended = rows.Int(kEnded) != 0;
    if (!ended && rows.Int(kNextIndex) == 0) break;  // started, nothing committed yet
    WaveRecord wave = impl.ReadWave(rows, static_cast<int>(history.waves.size()));
    if (__builtin_add_overflow(simulations, wave.candidates, &simulations) ||
        __builtin_add_overflow(discarded, wave.discarded, &discarded)) {
      throw Error(
          ErrorKind::kData, "corrupt run history: simulation counts overflow", impl.db.path());
    }
    history.waves.push_back(std::move(wave));
    if (!ended || !history.waves.back().complete) {
      rows.Reset();
      break;  // at most one incomplete wave, and it is the last
    }
  }
  // Not stored: the move waves' Eve indices, from their ancestors, which their Monte-Carlo errors
  // (export, answer, Python) cluster by.
  AssignEveIndices(history.waves);

  const RunMetadata metadata = LoadMetadata();
  if (!history.waves.empty() && history.waves.back().marginals_paper.empty() &&
      !history.waves.back().particles.empty()) {
    // A wave cut short before OnWaveEnd has no stored statistics: derive them from its particles,
    // as the engine does, so that reports can show it.
    const Estimator estimator =
        ParseEnum<Estimator>(metadata.estimator).value_or(Estimator::kPaper);
    ComputeWaveStatistics(history.waves.back(), estimator);
  }
  RunSummary& summary = history.summary;
  Statement run(impl.db, R"sql(
    SELECT waves_completed, simulations, simulations_discarded, wall_seconds FROM run
    WHERE id = 1)sql");
  run.Step();
  if (!run.IsNull(0)) {
    summary.waves_completed = static_cast<int>(run.Int(0));
    summary.simulations = run.Int(1);
    summary.simulations_discarded = run.Int(2);
    summary.wall_seconds = run.Real(3);
  } else {
    // Not finished (still running, killed or failed): summarise what was committed.
    for (const WaveRecord& wave : history.waves) summary.waves_completed += wave.complete ? 1 : 0;
    summary.simulations = simulations;
    summary.simulations_discarded = discarded;
  }
  for (const WaveRecord& wave : history.waves) {
    summary.failures += static_cast<std::int64_t>(wave.failures.size());
  }
  run.Reset();
  if (const auto termination = ParseEnum<Termination>(metadata.termination)) {
    summary.termination = *termination;
  } else if (metadata.status == RunStatus::kInterrupted) {
    summary.termination = Termination::kInterrupted;
  }
  summary.message = metadata.summary_message;
  return history;
}

ResumePoint HistoryStore::BeginResume(
    const std::vector<std::pair<std::string, std::string>>& stop_limits) {
  Impl& impl = *impl_;
  impl.RequireWritable("resume the run");
  {
    history::Transaction transaction(impl.db);
    // Everything the resume keeps is checked before anything is rewritten: re-hashing a corrupt
    // partial wave would make its corruption look valid.
    LoadResumePoint();
    const std::optional<Impl::PartialWave> partial = impl.FindPartial();
    if (partial) {
      // Waves after the partial one cannot be valid (the engine writes them in order).
      Statement later_particles(impl.db, "DELETE FROM particle WHERE wave > ?1");
      later_particles.Bind(1, partial->wave).Run();
      Statement later_failures(impl.db, "DELETE FROM failure WHERE wave > ?1");
      later_failures.Bind(1, partial->wave).Run();
      Statement later_waves(impl.db, "DELETE FROM wave WHERE wave > ?1");
      later_waves.Bind(1, partial->wave).Run();
      if (partial->next_index == 0) {
        Statement drop(impl.db, "DELETE FROM particle WHERE wave = ?1");
        drop.Bind(1, partial->wave).Run();
        Statement drop_failures(impl.db, "DELETE FROM failure WHERE wave = ?1");
        drop_failures.Bind(1, partial->wave).Run();
        Statement drop_wave(impl.db, "DELETE FROM wave WHERE wave = ?1");
        drop_wave.Bind(1, partial->wave).Run();
      } else {
        Statement beyond(impl.db, "DELETE FROM particle WHERE wave = ?1 AND candidate >= ?2");
        beyond.Bind(1, partial->wave).Bind(2, partial->next_index).Run();
        Statement beyond_failures(impl.db,
                                  "DELETE FROM failure WHERE wave = ?1 AND candidate >= ?2");
        beyond_failures.Bind(1, partial->wave).Bind(2, partial->next_index).Run();
        // Its end-of-wave statistics (an interrupted wave) are rewritten when it really ends; its
        // multi-fidelity costs are its last batch's (the wave ended where that batch did).
        Statement reopen(impl.db, R"sql(
          UPDATE wave SET ended = 0, complete = 0, candidates = NULL, accepted = NULL,
            acceptance_rate = NULL, marginals_paper = NULL, marginals_importance = NULL,
            ess = NULL, distinct_count = NULL, wall_seconds = NULL, ended_at = NULL,
            reals_mean = NULL, reals_sd = NULL, next_continue_if_accepted = NULL,
            next_continue_if_rejected = NULL, cost_ratio = NULL, move_survivor_ess = NULL,
            move_step = NULL, move_rounds = NULL, move_proposed = NULL, move_accepted = NULL,
            move_independent_proposed = NULL, move_independent_accepted = NULL
          WHERE wave = ?1)sql");
        reopen.Bind(1, partial->wave).Run();
        impl.chain.wave = -1;
        impl.StoreWaveHash(partial->wave);
      }
    }
    impl.db.Exec(R"sql(
      UPDATE run SET status = 'running', resume_count = resume_count + 1, end_time = '',
        termination = '', message = '', waves_completed = NULL, simulations = NULL,
        simulations_discarded = NULL, wall_seconds = NULL WHERE id = 1)sql");
    Statement limit(impl.db, "INSERT OR REPLACE INTO meta (key, value) VALUES (?1, ?2)");
    for (const auto& [key, value] : stop_limits) {
      limit.Bind(1, "stop_limit_" + key).Bind(2, value).Run();
    }
    impl.StoreRunHashes();
    transaction.Commit();
  }
  return LoadResumePoint();
}

}  // namespace combabc
