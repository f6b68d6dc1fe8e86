// Reading a run history back: metadata, waves, the resume point, and truncation for resume.
#include <cstdlib>

#include "combabc/core/error.hpp"
#include "history/history_impl.hpp"

namespace combabc {
namespace {

using history::Statement;
using history::UnpackBits;
using history::UnpackDoubles;

constexpr const char* kWaveColumns = R"sql(
SELECT wave, thresholds, phi, proposal, next_index, accepted_so_far, ended, complete,
  candidates, accepted, acceptance_rate, marginals_paper, marginals_importance, ess,
  distinct_count, wall_seconds
FROM wave)sql";

enum WaveColumn {
  kWave,
  kThresholds,
  kPhi,
  kProposal,
  kNextIndex,
  kAcceptedSoFar,
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
};

}  // namespace

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

std::vector<Particle> HistoryStore::Impl::LoadParticles(int wave, std::int64_t below_index) {
  Statement s(db, R"sql(
    SELECT candidate, bits, log_weight, weight, distance, output FROM particle
    WHERE wave = ?1 AND candidate < ?2 ORDER BY candidate)sql");
  s.Bind(1, wave).Bind(2, below_index);
  std::vector<Particle> particles;
  while (s.Step()) {
    Particle p;
    p.index = s.Int(0);
    p.bits = UnpackBits(s.Blob(1), dimension, db.path());
    p.log_weight = s.Real(2);
    p.weight = s.Real(3);
    p.distance = UnpackDoubles(s.Blob(4), db.path());
    p.output = UnpackDoubles(s.Blob(5), db.path());
    particles.push_back(std::move(p));
  }
  return particles;
}

WaveRecord HistoryStore::Impl::LoadWave(Statement& row, bool with_statistics) {
  WaveRecord wave;
  wave.wave = static_cast<int>(row.Int(kWave));
  wave.thresholds = UnpackDoubles(row.Blob(kThresholds), db.path());
  wave.phi = row.Real(kPhi);
  wave.proposal = UnpackDoubles(row.Blob(kProposal), db.path());
  if (with_statistics) {
    wave.complete = row.Int(kComplete) != 0;
    wave.candidates = row.Int(kCandidates);
    wave.accepted = row.Int(kAccepted);
    wave.acceptance_rate = row.Real(kAcceptanceRate);
    wave.marginals_paper = UnpackDoubles(row.Blob(kMarginalsPaper), db.path());
    wave.marginals_importance = UnpackDoubles(row.Blob(kMarginalsImportance), db.path());
    wave.ess = row.Real(kEss);
    wave.distinct = row.Int(kDistinct);
    wave.wall_seconds = row.Real(kWallSeconds);
  } else {
    // A wave cut short before OnWaveEnd: only its progress is known (LoadHistory derives the
    // rest from the particles).
    wave.candidates = row.Int(kNextIndex);
    wave.accepted = row.Int(kAcceptedSoFar);
    wave.acceptance_rate = wave.candidates > 0 ? static_cast<double>(wave.accepted) /
                                                     static_cast<double>(wave.candidates)
                                               : 0.0;
  }
  return wave;
}

RunMetadata HistoryStore::LoadMetadata() const {
  history::Database& db = impl_->db;
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
    c.kind =
        components.Text(1) == "indicator" ? ComponentKind::kIndicator : ComponentKind::kThreshold;
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
  return m;
}

ResumePoint HistoryStore::LoadResumePoint() const {
  Impl& impl = *impl_;
  ResumePoint point;
  Statement rows(impl.db, (std::string(kWaveColumns) + " ORDER BY wave").c_str());
  while (rows.Step()) {
    const bool ended = rows.Int(kEnded) != 0;
    const bool complete = rows.Int(kComplete) != 0;
    if (ended && complete) {
      point.completed.push_back(impl.LoadWave(rows, /*with_statistics=*/true));
      continue;
    }
    // The first incomplete wave is where the run continues; nothing after it counts. A wave
    // started without any committed batch is simply started again.
    const std::int64_t next_index = rows.Int(kNextIndex);
    if (next_index > 0) {
      point.has_partial = true;
      point.partial_wave = static_cast<int>(rows.Int(kWave));
      point.partial_next_index = next_index;
    }
    rows.Reset();
    break;
  }
  for (WaveRecord& wave : point.completed) {
    wave.particles = impl.LoadParticles(wave.wave, INT64_MAX);
  }
  if (point.has_partial) {
    point.partial_accepted = impl.LoadParticles(point.partial_wave, point.partial_next_index);
  }
  return point;
}

RunHistory HistoryStore::LoadHistory() const {
  Impl& impl = *impl_;
  RunHistory history;
  Statement rows(impl.db, (std::string(kWaveColumns) + " ORDER BY wave").c_str());
  std::int64_t simulations = 0;
  while (rows.Step()) {
    const bool ended = rows.Int(kEnded) != 0;
    if (!ended && rows.Int(kNextIndex) == 0) break;  // started, nothing committed yet
    WaveRecord wave = impl.LoadWave(rows, ended);
    simulations += wave.candidates;
    history.waves.push_back(std::move(wave));
    if (!ended || !history.waves.back().complete) {
      rows.Reset();
      break;  // at most one incomplete wave, and it is the last
    }
  }
  // OnBatch commits particles with their progress, so every stored particle lies below next_index.
  for (WaveRecord& wave : history.waves) wave.particles = impl.LoadParticles(wave.wave, INT64_MAX);

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

ResumePoint HistoryStore::BeginResume() {
  Impl& impl = *impl_;
  impl.RequireWritable("resume the run");
  {
    history::Transaction transaction(impl.db);
    const std::optional<Impl::PartialWave> partial = impl.FindPartial();
    if (partial) {
      // Waves after the partial one cannot be valid (the engine writes them in order).
      Statement later_particles(impl.db, "DELETE FROM particle WHERE wave > ?1");
      later_particles.Bind(1, partial->wave).Run();
      Statement later_waves(impl.db, "DELETE FROM wave WHERE wave > ?1");
      later_waves.Bind(1, partial->wave).Run();
      if (partial->next_index == 0) {
        Statement drop(impl.db, "DELETE FROM particle WHERE wave = ?1");
        drop.Bind(1, partial->wave).Run();
        Statement drop_wave(impl.db, "DELETE FROM wave WHERE wave = ?1");
        drop_wave.Bind(1, partial->wave).Run();
      } else {
        Statement beyond(impl.db, "DELETE FROM particle WHERE wave = ?1 AND candidate >= ?2");
        beyond.Bind(1, partial->wave).Bind(2, partial->next_index).Run();
        // Its end-of-wave statistics (an interrupted wave) are rewritten when it really ends.
        Statement reopen(impl.db, R"sql(
          UPDATE wave SET ended = 0, complete = 0, candidates = NULL, accepted = NULL,
            acceptance_rate = NULL, marginals_paper = NULL, marginals_importance = NULL,
            ess = NULL, distinct_count = NULL, wall_seconds = NULL, ended_at = NULL
          WHERE wave = ?1)sql");
        reopen.Bind(1, partial->wave).Run();
      }
    }
    impl.db.Exec(R"sql(
      UPDATE run SET status = 'running', resume_count = resume_count + 1, end_time = '',
        termination = '', message = '', waves_completed = NULL, simulations = NULL,
        simulations_discarded = NULL, wall_seconds = NULL WHERE id = 1)sql");
    transaction.Commit();
  }
  return LoadResumePoint();
}

}  // namespace combabc
