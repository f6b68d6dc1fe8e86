#include "history_seed.hpp"

#include <sqlite3.h>

#include <cstdint>
#include <vector>

#include "combabc/core/error.hpp"
#include "combabc/history/history_store.hpp"
#include "fuzz_util.hpp"

namespace combabc::fuzz {
namespace {

constexpr int kDimension = 6;

Particle MakeParticle(std::int64_t index, std::vector<std::uint8_t> bits, double distance) {
  Particle p;
  p.index = index;
  p.theta.bits = std::move(bits);
  p.theta.reals = {0.05 + 0.1 * static_cast<double>(index)};
  p.log_weight = -0.1 * static_cast<double>(index);
  p.weight = 0.25;
  p.distance = {distance, 1.0};
  p.output = {0.1, 1.0, 0.5, 0.2};
  return p;
}

// `number` is 0-based, as the engine numbers waves (and Open requires rows 0 .. n-1).
WaveRecord MakeWave(int number, double threshold) {
  WaveRecord wave;
  wave.wave = number;
  wave.thresholds = {threshold};
  wave.phi = number == 0 ? 0.0 : 0.5;
  wave.proposal = std::vector<double>(kDimension, number == 0 ? 0.5 : 0.7);
  return wave;
}

}  // namespace

void WriteSeedHistory(const std::string& path) {
  RunMetadata m;
  m.config_text = "# fuzz seed\n[sampler]\nwaves = 2\naccepted_per_wave = 4\n";
  m.config_path = "seed.toml";
  m.combabc_version = "0.1.0";
  m.git_hash = "fuzzseed";
  m.seed = 42;
  m.threads = 1;
  m.start_time = "2024-01-01T00:00:00Z";
  m.estimator = "importance";
  m.dimension = kDimension;
  m.bit_names = {"clamp 1", "clamp 2", "clamp 3", "clamp 4", "clamp 5", "clamp 6"};
  m.bit_prior_one = std::vector<double>(kDimension, 0.5);
  m.distance_components = {{"least_squares", ComponentKind::kThreshold, 1.0},
                           {"peak", ComponentKind::kIndicator, 1.0}};
  m.output_positions = {0.0, 0.3, 0.6, 0.9};
  m.position_unit = "m";
  m.measured.positions = {0.5, 0.6, 0.7};
  m.measured.values = {1.0, 0.5, 0.25};
  // Schema v3's additions, so that the patch fuzzer mutates them too.
  m.reals = {{"stiffness", {PriorKind::kUniform, 0.0, 1.0, 0.0, 1.0}}};
  m.proposal.binary = BinaryKernelKind::kLogistic;
  m.tempering_form = "geometric";
  m.fingerprint = {{"combined", "0123456789abcdef"}, {"data", "fedcba9876543210"}};
  // Schema v6: two experiments, each with its slice of the outputs, points and components.
  m.experiments = {{"left", "load at 0.3 m", 2, 1, 1}, {"right", "load at 0.6 m", 2, 2, 1}};

  RemoveDatabase(path);
  {
    HistoryStore store = HistoryStore::Create(path, m, /*overwrite=*/true);
    // Wave 1: two batches, then ended and complete with final weights and statistics.
    WaveRecord one = MakeWave(0, 0.5);
    store.OnWaveStart(one);
    std::vector<Particle> first = {MakeParticle(0, {1, 0, 1, 0, 1, 0}, 0.2),
                                   MakeParticle(2, {0, 1, 1, 0, 0, 1}, 0.4)};
    std::vector<Particle> second = {MakeParticle(3, {1, 1, 0, 0, 1, 1}, 0.1),
                                    MakeParticle(5, {0, 0, 0, 1, 1, 1}, 0.3)};
    store.OnBatch({0, 4, 2, 0, 4, 4, 0.0, 0, {}}, first);
    store.OnBatch({0, 6, 4, 0, 4, 6, 0.0, 0, {}}, second);
    one.particles = first;
    one.particles.insert(one.particles.end(), second.begin(), second.end());
    one.candidates = 6;
    one.accepted = 4;
    one.acceptance_rate = 4.0 / 6.0;
    one.complete = true;
    one.marginals_paper = {0.5, 0.5, 0.5, 0.25, 0.75, 0.75};
    one.marginals_importance = {0.5, 0.5, 0.5, 0.25, 0.75, 0.75};
    one.ess = 3.5;
    one.reals_mean = {0.3};
    one.reals_sd = {0.2};
    one.distinct = 4;
    one.wall_seconds = 0.01;
    store.OnWaveEnd(one);
    // Wave 2: one batch committed, then the "process was killed".
    WaveRecord two = MakeWave(1, 0.3);
    // Schema v8: two pattern classes of wave 1, the second flagged.
    two.pattern_classes = {{{1, 0, 1, 0, 1, 0}, 0.6, 0.5, false},
                           {{0, 1, 1, 0, 0, 1}, 0.3, 1e-4, true}};
    // Schema v10: a resample-move wave, its particles moved from wave 1's particles 0 and 3.
    two.moves = WaveMoves{2.5, 0.75, 1, 3, 2, 1, 1};
    store.OnWaveStart(two);
    std::vector<Particle> moved = {MakeParticle(0, {1, 0, 1, 1, 1, 0}, 0.1),
                                   MakeParticle(1, {1, 0, 0, 0, 1, 0}, 0.2)};
    moved[0].ancestor = 0;
    moved[1].ancestor = 3;
    store.OnBatch({1, 3, 2, 0, 4, 9, 0.0, 0, {}}, moved);
  }
  // One small self-contained file: fold the WAL back, leave WAL mode, use 512-byte pages.
  sqlite3* db = nullptr;
  if (sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READWRITE, nullptr) != SQLITE_OK ||
      sqlite3_exec(db,
                   "PRAGMA wal_checkpoint(TRUNCATE); PRAGMA journal_mode = DELETE;"
                   "PRAGMA page_size = 512; VACUUM;",
                   nullptr,
                   nullptr,
                   nullptr) != SQLITE_OK) {
    const std::string why = db != nullptr ? sqlite3_errmsg(db) : "out of memory";
    sqlite3_close(db);
    throw Error(ErrorKind::kIo, "cannot compact the seed history: " + why, path);
  }
  sqlite3_close(db);
}

}  // namespace combabc::fuzz
