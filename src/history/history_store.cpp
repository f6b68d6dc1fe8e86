// Recording a run into its history: the SmcObserver callbacks, Finish and MarkFailed.
#include <algorithm>
#include <cstdint>
#include <set>

#include "combabc/core/error.hpp"
#include "history/history_impl.hpp"

namespace combabc {
namespace {

using history::PackBits;
using history::PackDoubles;
using history::Statement;
using history::Transaction;

// A multi-fidelity wave starts with its continuation probabilities and no cost; recorded again
// (resume, OnWaveEnd), it keeps the costs its batches recorded. A resample-move wave's move
// statistics are the record's each time (OnWaveEnd's final).
constexpr const char* kUpsertWave = R"sql(
INSERT INTO wave (wave, thresholds, phi, proposal, started_at, continue_if_accepted,
  continue_if_rejected, expensive_simulations, cheap_seconds, expensive_seconds,
  unkept_false_positives, unkept_false_positive_log_w2, pattern_bits, pattern_mass,
  pattern_proposal, pattern_flagged, move_survivor_ess, move_step, move_rounds, move_proposed,
  move_accepted, move_independent_proposed, move_independent_accepted)
VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16, ?17, ?18, ?19,
  ?20, ?21, ?22, ?23)
ON CONFLICT (wave) DO UPDATE SET
  thresholds = excluded.thresholds, phi = excluded.phi, proposal = excluded.proposal,
  continue_if_accepted = excluded.continue_if_accepted,
  continue_if_rejected = excluded.continue_if_rejected, pattern_bits = excluded.pattern_bits,
  pattern_mass = excluded.pattern_mass, pattern_proposal = excluded.pattern_proposal,
  pattern_flagged = excluded.pattern_flagged, move_survivor_ess = excluded.move_survivor_ess,
  move_step = excluded.move_step, move_rounds = excluded.move_rounds,
  move_proposed = excluded.move_proposed, move_accepted = excluded.move_accepted,
  move_independent_proposed = excluded.move_independent_proposed,
  move_independent_accepted = excluded.move_independent_accepted
)sql";

// Re-sending a particle (OnWaveEnd's normalised weights) replaces it, but an output already stored
// is kept when the new record carries none.
constexpr const char* kUpsertParticle = R"sql(
INSERT INTO particle (wave, candidate, bits, log_weight, weight, distance, output, reals,
  multiplier, confirmed, low_distance, ancestor)
VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12)
ON CONFLICT (wave, candidate) DO UPDATE SET
  bits = excluded.bits, log_weight = excluded.log_weight, weight = excluded.weight,
  distance = excluded.distance, output = COALESCE(excluded.output, particle.output),
  reals = excluded.reals, multiplier = excluded.multiplier, confirmed = excluded.confirmed,
  low_distance = excluded.low_distance, ancestor = excluded.ancestor
)sql";

// A multi-fidelity batch also records the wave's costs so far (BatchProgress::fidelity); a
// single-fidelity one binds NULL there and leaves the columns as they are.
constexpr const char* kUpdateProgress = R"sql(
UPDATE wave SET next_index = ?2, accepted_so_far = ?3, accepted_needed = ?4,
  total_simulations = ?5, discarded = ?6, failures = ?7,
  continue_if_accepted = COALESCE(?8, continue_if_accepted),
  continue_if_rejected = COALESCE(?9, continue_if_rejected),
  expensive_simulations = COALESCE(?10, expensive_simulations),
  cheap_seconds = COALESCE(?11, cheap_seconds),
  expensive_seconds = COALESCE(?12, expensive_seconds),
  unkept_false_positives = COALESCE(?13, unkept_false_positives),
  unkept_false_positive_log_w2 = COALESCE(?14, unkept_false_positive_log_w2)
WHERE wave = ?1
)sql";

constexpr const char* kUpsertFailure = R"sql(
INSERT OR REPLACE INTO failure (wave, candidate, reason) VALUES (?1, ?2, ?3)
)sql";

// A particle of a multi-fidelity run has a cheap distance; in a single-fidelity run its
// multi-fidelity columns are NULL. Its ancestor is NULL when it was drawn afresh (-1).
void BindParticle(Statement& s, int wave, const Particle& p) {
  s.Bind(1, wave)
      .Bind(2, p.index)
      .BindBytes(3, PackBits(p.theta.bits))
      .Bind(4, p.log_weight)
      .Bind(5, p.weight)
      .BindBlob(6, PackDoubles(p.distance))
      .BindBlob(7, PackDoubles(p.output))
      .BindBlob(8, PackDoubles(p.theta.reals));
  if (!p.low_distance.empty()) {
    s.Bind(9, p.multiplier).Bind(10, p.confirmed ? 1 : 0).BindBlob(11, PackDoubles(p.low_distance));
  } else {
    s.BindNull(9).BindNull(10).BindNull(11);
  }
  if (p.ancestor >= 0) {
    s.Bind(12, p.ancestor);
  } else {
    s.BindNull(12);
  }
}

// The move statistics from `first` on; NULL in a rejection wave.
void BindMoves(Statement& s, int first, const std::optional<WaveMoves>& m) {
  if (!m) {
    for (int c = first; c < first + 7; ++c) s.BindNull(c);
    return;
  }
  s.Bind(first, m->survivor_ess)
      .Bind(first + 1, m->step)
      .Bind(first + 2, m->rounds)
      .Bind(first + 3, m->proposed)
      .Bind(first + 4, m->accepted)
      .Bind(first + 5, m->independent_proposed)
      .Bind(first + 6, m->independent_accepted);
}

// The multi-fidelity columns from `first` on: the continuation probabilities, the expensive count
// and the two costs, then (`ended`) the next wave's probabilities and the cost ratio; NULL without.
void BindFidelity(Statement& s, int first, const std::optional<WaveFidelity>& f, bool ended) {
  if (f) {
    s.Bind(first, f->continue_if_accepted)
        .Bind(first + 1, f->continue_if_rejected)
        .Bind(first + 2, f->expensive_simulations)
        .Bind(first + 3, f->cheap_seconds)
        .Bind(first + 4, f->expensive_seconds)
        .Bind(first + 5, f->unkept_false_positives)
        .Bind(first + 6, f->unkept_false_positive_log_w2);
    if (ended) {
      s.Bind(first + 7, f->next_continue_if_accepted)
          .Bind(first + 8, f->next_continue_if_rejected)
          .Bind(first + 9, f->cost_ratio);
    }
    return;
  }
  for (int c = first; c < first + (ended ? 10 : 7); ++c) s.BindNull(c);
}

// A wrong bit or real count would only surface when the run is read back; refuse it when written.
void CheckTheta(const HistoryShape& shape,
                const std::string& path,
                std::span<const Particle> particles) {
  for (const Particle& p : particles) {
    if (p.theta.bits.size() != static_cast<std::size_t>(shape.dimension) ||
        p.theta.reals.size() != shape.reals) {
      throw Error(ErrorKind::kSoftware,
                  "particle " + std::to_string(p.index) + " has " +
                      std::to_string(p.theta.bits.size()) + " bits and " +
                      std::to_string(p.theta.reals.size()) + " reals, the run has " +
                      std::to_string(shape.dimension) + " and " + std::to_string(shape.reals),
                  path);
    }
  }
}

// The wave's pattern classes from `first` on (docs/history.md, "Mode loss"); NULL without any.
void BindPatternClasses(Statement& s, int first, const std::vector<PatternClass>& classes) {
  if (classes.empty()) {
    for (int c = first; c < first + 4; ++c) s.BindNull(c);
    return;
  }
  std::vector<std::uint8_t> bits;
  std::vector<double> mass;
  std::vector<double> proposal;
  std::vector<std::uint8_t> flagged;
  // A wave with a class of one or two bits' values (v9) stores each class's bits (kAnyBit as 0)
  // and then its mask (1 where the class fixes the bit); a wave of whole patterns only, the bits
  // alone, as v8 did.
  const bool masked = std::any_of(classes.begin(), classes.end(), [](const PatternClass& c) {
    return std::find(c.bits.begin(), c.bits.end(), kAnyBit) != c.bits.end();
  });
  for (const PatternClass& c : classes) {
    std::vector<std::uint8_t> value(c.bits.size()), fixed(c.bits.size());
    for (std::size_t k = 0; k < c.bits.size(); ++k) {
      value[k] = c.bits[k] == 1 ? 1 : 0;
      fixed[k] = c.bits[k] == kAnyBit ? 0 : 1;
    }
    const auto packed = PackBits(value);
    bits.insert(bits.end(), packed.begin(), packed.end());
    if (masked) {
      const auto mask = PackBits(fixed);
      bits.insert(bits.end(), mask.begin(), mask.end());
    }
    mass.push_back(c.mass);
    proposal.push_back(c.proposal);
    flagged.push_back(c.flagged ? 1 : 0);
  }
  s.BindBytes(first, bits)
      .BindBlob(first + 1, PackDoubles(mass))
      .BindBlob(first + 2, PackDoubles(proposal))
      .BindBytes(first + 3, flagged);
}

void UpsertWave(history::Database& db, const WaveRecord& wave) {
  Statement s(db, kUpsertWave);
  s.Bind(1, wave.wave)
      .BindBlob(2, PackDoubles(wave.thresholds))
      .Bind(3, wave.phi)
      .BindBlob(4, PackDoubles(wave.proposal))
      .Bind(5, history::UtcNow());
  BindFidelity(s, 6, wave.multi_fidelity, /*ended=*/false);
  BindPatternClasses(s, 13, wave.pattern_classes);
  BindMoves(s, 17, wave.moves);
  s.Run();
}

}  // namespace

// A failure sent again (OnWaveEnd) below the hashed chain means hashing the wave anew.
void HistoryStore::Impl::InsertFailures(int wave, std::span<const SimulationFailure> rows) {
  if (rows.empty()) return;
  if (!upsert_failure) upsert_failure.emplace(db, kUpsertFailure);
  for (const SimulationFailure& f : rows) {
    upsert_failure->Bind(1, wave).Bind(2, f.index).Bind(3, f.reason).Run();
    if (chain.wave == wave && f.index < chain.next_failure) chain.wave = -1;
  }
}

void HistoryStore::Impl::ExtendWaveChain(int wave) {
  if (chain.wave != wave) {
    chain = WaveChain{};
    chain.wave = wave;
    chain.next_candidate = INT64_MIN;
    chain.next_failure = INT64_MIN;
  }
  Statement rows(
      db, (ParticleSelect() + " WHERE wave = ?1 AND candidate >= ?2 ORDER BY candidate").c_str());
  rows.Bind(1, wave).Bind(2, chain.next_candidate);
  while (rows.Step()) {
    chain.hasher.AddParticle(rows);
    chain.next_candidate = rows.Int(0) + 1;
  }
  if (!has_failures()) return;
  Statement failures(db,
                     (std::string("SELECT ") + history::kFailureColumns +
                      " FROM failure WHERE wave = ?1 AND candidate >= ?2 ORDER BY candidate")
                         .c_str());
  failures.Bind(1, wave).Bind(2, chain.next_failure);
  while (failures.Step()) {
    chain.hasher.AddFailure(failures);
    chain.next_failure = failures.Int(0) + 1;
  }
}

// Called inside the transaction that changed the wave, so that the checksum commits with it.
void HistoryStore::Impl::StoreWaveHash(int wave) {
  ExtendWaveChain(wave);
  Statement row(db, (WaveSelect() + " WHERE wave = ?1").c_str());
  row.Bind(1, wave);
  if (!row.Step()) return;
  const std::string digest = history::HexDigest(chain.hasher.Finish(row));
  row.Reset();
  Statement store(db, "UPDATE wave SET content_hash = ?2 WHERE wave = ?1");
  store.Bind(1, wave).Bind(2, digest).Run();
}

void HistoryStore::Impl::RequireWritable(const char* what) {
  if (read_only) {
    throw Error(ErrorKind::kSoftware,
                std::string("run history opened read-only; cannot ") + what,
                db.path());
  }
  PrepareWrite();
}

void HistoryStore::OnWaveStart(const WaveRecord& wave) {
  impl_->RequireWritable("record a wave");
  Transaction transaction(impl_->db);
  UpsertWave(impl_->db, wave);
  impl_->StoreWaveHash(wave.wave);
  // The wave count goes with the new row: waves deleted by hand are then told from unwritten ones.
  impl_->StoreRunStateHash();
  transaction.Commit();
}

void HistoryStore::OnBatch(const BatchProgress& progress, std::span<const Particle> accepted) {
  Impl& impl = *impl_;
  impl.RequireWritable("record a batch");
  if (!impl.upsert_particle) impl.upsert_particle.emplace(impl.db, kUpsertParticle);
  if (!impl.update_progress) impl.update_progress.emplace(impl.db, kUpdateProgress);
  CheckTheta(impl.shape, impl.db.path(), accepted);
  // Particles and progress commit together: after this, next_index is a valid restart point.
  Transaction transaction(impl.db);
  impl.update_progress->Bind(1, progress.wave)
      .Bind(2, progress.next_index)
      .Bind(3, progress.accepted)
      .Bind(4, progress.accepted_needed)
      .Bind(5, progress.total_simulations)
      .Bind(6, progress.discarded)
      .Bind(7, progress.failures);
  BindFidelity(*impl.update_progress, 8, progress.fidelity, /*ended=*/false);
  impl.update_progress->Run();
  if (impl.db.Changes() == 0) {
    throw Error(ErrorKind::kSoftware,
                "batch for wave " + std::to_string(progress.wave) + " before its OnWaveStart",
                impl.db.path());
  }
  for (const Particle& p : accepted) {
    BindParticle(*impl.upsert_particle, progress.wave, p);
    impl.upsert_particle->Run();
    // The checksum extends over new particles only; one sent again means hashing the wave anew.
    if (impl.chain.wave == progress.wave && p.index < impl.chain.next_candidate) {
      impl.chain.wave = -1;
    }
  }
  impl.InsertFailures(progress.wave, progress.failed);
  impl.StoreWaveHash(progress.wave);
  transaction.Commit();
}

void HistoryStore::OnWaveEnd(const WaveRecord& wave) {
  Impl& impl = *impl_;
  impl.RequireWritable("record a wave");
  if (!impl.upsert_particle) impl.upsert_particle.emplace(impl.db, kUpsertParticle);
  CheckTheta(impl.shape, impl.db.path(), wave.particles);
  Transaction transaction(impl.db);
  UpsertWave(impl.db, wave);
  Statement end(impl.db, R"sql(
    UPDATE wave SET ended = 1, complete = ?2, candidates = ?3, accepted = ?4,
      acceptance_rate = ?5, marginals_paper = ?6, marginals_importance = ?7, ess = ?8,
      distinct_count = ?9, wall_seconds = ?10, ended_at = ?11, discarded = ?12, reals_mean = ?13,
      reals_sd = ?14, failures = ?15, continue_if_accepted = ?16, continue_if_rejected = ?17,
      expensive_simulations = ?18, cheap_seconds = ?19, expensive_seconds = ?20,
      unkept_false_positives = ?21, unkept_false_positive_log_w2 = ?22,
      next_continue_if_accepted = ?23, next_continue_if_rejected = ?24, cost_ratio = ?25
    WHERE wave = ?1)sql");
  end.Bind(1, wave.wave)
      .Bind(2, wave.complete ? 1 : 0)
      .Bind(3, wave.candidates)
      .Bind(4, wave.accepted)
      .Bind(5, wave.acceptance_rate)
      .BindBlob(6, PackDoubles(wave.marginals_paper))
      .BindBlob(7, PackDoubles(wave.marginals_importance))
      .Bind(8, wave.ess)
      .Bind(9, wave.distinct)
      .Bind(10, wave.wall_seconds)
      .Bind(11, history::UtcNow())
      .Bind(12, wave.discarded)
      .BindBlob(13, PackDoubles(wave.reals_mean))
      .BindBlob(14, PackDoubles(wave.reals_sd))
      .Bind(15, static_cast<std::int64_t>(wave.failures.size()));
  BindFidelity(end, 16, wave.multi_fidelity, /*ended=*/true);
  end.Run();
  impl.InsertFailures(wave.wave, wave.failures);
  // Like its particles, the wave's final list of failures is the truth.
  Statement beyond(impl.db, "DELETE FROM failure WHERE wave = ?1 AND candidate >= ?2");
  beyond.Bind(1, wave.wave).Bind(2, wave.candidates).Run();
  std::set<std::int64_t> kept;
  for (const Particle& p : wave.particles) {
    BindParticle(*impl.upsert_particle, wave.wave, p);
    impl.upsert_particle->Run();
    kept.insert(p.index);
  }
  // The wave's final list is the truth: drop batch particles it did not keep (parallel overshoot).
  Statement stored(impl.db, "SELECT candidate FROM particle WHERE wave = ?1");
  stored.Bind(1, wave.wave);
  std::vector<std::int64_t> dropped;
  while (stored.Step()) {
    if (kept.count(stored.Int(0)) == 0) dropped.push_back(stored.Int(0));
  }
  Statement drop(impl.db, "DELETE FROM particle WHERE wave = ?1 AND candidate = ?2");
  for (std::int64_t index : dropped) drop.Bind(1, wave.wave).Bind(2, index).Run();
  // Weights were rewritten and particles dropped: the final checksum is computed afresh.
  impl.chain.wave = -1;
  impl.StoreWaveHash(wave.wave);
  impl.chain.wave = -1;
  transaction.Commit();
}

void HistoryStore::Finish(const RunSummary& summary) {
  Impl& impl = *impl_;
  impl.RequireWritable("finish the run");
  const RunStatus status = summary.termination == Termination::kInterrupted
                               ? RunStatus::kInterrupted
                               : RunStatus::kFinished;
  {
    Transaction transaction(impl.db);
    Statement s(impl.db, R"sql(
      UPDATE run SET status = ?1, termination = ?2, message = ?3, waves_completed = ?4,
        simulations = ?5, simulations_discarded = ?6, wall_seconds = ?7, end_time = ?8
      WHERE id = 1)sql");
    s.Bind(1, std::string(ToString(status)))
        .Bind(2, std::string(ToString(summary.termination)))
        .Bind(3, summary.message)
        .Bind(4, summary.waves_completed)
        .Bind(5, summary.simulations)
        .Bind(6, summary.simulations_discarded)
        .Bind(7, summary.wall_seconds)
        .Bind(8, history::UtcNow())
        .Run();
    impl.StoreRunHashes();
    transaction.Commit();
  }
  // Fold the WAL back into the file and leave rollback-journal mode, so the finished RUN.sqlite is
  // one self-contained file that can be copied or opened read-only anywhere.
  impl.upsert_particle.reset();
  impl.update_progress.reset();
  impl.upsert_failure.reset();
  // Best effort: the summary is committed already, and a reader holding the file open (a report
  // of the running run) only means the WAL stays until the next open.
  impl.db.TryExec("PRAGMA wal_checkpoint(TRUNCATE)");
  impl.db.TryExec("PRAGMA journal_mode = DELETE");
}

void HistoryStore::MarkFailed(const std::string& message) {
  Impl& impl = *impl_;
  impl.RequireWritable("mark the run failed");
  Transaction transaction(impl.db);
  Statement s(impl.db, "UPDATE run SET status = ?1, message = ?2, end_time = ?3 WHERE id = 1");
  s.Bind(1, std::string(ToString(RunStatus::kFailed)))
      .Bind(2, message)
      .Bind(3, history::UtcNow())
      .Run();
  impl.StoreRunHashes();
  transaction.Commit();
}

}  // namespace combabc
