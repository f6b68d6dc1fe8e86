#pragma once
// HistoryStore's state, shared by history_store.cpp (create, open, record) and history_load.cpp
// (load, resume). Private to src/history.
#include <optional>
#include <string>

#include "combabc/history/history_store.hpp"
#include "history/history_sqlite.hpp"

namespace combabc {

// 'CBAB' in the SQLite header's application_id: tells a combabc history from any other database.
inline constexpr int kHistoryApplicationId = 0x43424142;

struct HistoryStore::Impl {
  Impl(const std::string& path, bool create, bool read_only_in)
      : db(path, create, read_only_in), read_only(read_only_in) {}

  // The database outlives the statements prepared on it (members are destroyed in reverse order).
  history::Database db;
  bool read_only = false;
  int dimension = 0;
  std::optional<history::Statement> upsert_particle;
  std::optional<history::Statement> update_progress;

  void RequireWritable(const char* what) const;
  // The first wave that is not complete and its next_index; nullopt when every wave is complete.
  struct PartialWave {
    int wave = 0;
    std::int64_t next_index = 0;
    bool ended = false;
  };
  std::optional<PartialWave> FindPartial();
  WaveRecord LoadWave(history::Statement& row, bool with_statistics);
  std::vector<Particle> LoadParticles(int wave, std::int64_t below_index);
};

}  // namespace combabc
