#pragma once
// Helpers for the end-to-end tests of what commands write: synthetic histories (no FE model),
// directory listings, and a scoped working directory and environment for the child CLI.
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <functional>
#include <set>
#include <string>

#include "combabc/history/history_store.hpp"
#include "history/fake_run.hpp"

namespace combabc::testing {

// A finished synthetic run of `waves` waves (36 clamps, curves stored) at `path`; `edit` may change
// its metadata (config text, names) or waves before it is written.
inline std::string MakeHistory(const std::filesystem::path& path,
                               const std::function<void(RunMetadata&, RunHistory&)>& edit = {},
                               int waves = 2) {
  FakeRunOptions options;
  options.waves = waves;
  options.per_wave = 30;
  RunMetadata metadata = MakeFakeMetadata(options);
  RunHistory history = MakeFakeHistory(options);
  if (edit) edit(metadata, history);
  HistoryStore store = HistoryStore::Create(path.string(), metadata);
  for (const WaveRecord& wave : history.waves) RecordWave(store, wave, 10);
  store.Finish(history.summary);
  return path.string();
}

inline std::set<std::string> Listing(const std::filesystem::path& dir) {
  std::set<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    names.insert(entry.path().filename().string());
  }
  return names;
}

// The test process's working directory (which the CLI child inherits), restored on exit.
class ScopedWorkingDirectory {
 public:
  explicit ScopedWorkingDirectory(const std::filesystem::path& dir)
      : saved_(std::filesystem::current_path()) {
    std::filesystem::current_path(dir);
  }
  ~ScopedWorkingDirectory() { std::filesystem::current_path(saved_); }

 private:
  std::filesystem::path saved_;
};

// An environment variable for the CLI child, restored on exit.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const std::string& value) : name_(name) {
    if (const char* old = std::getenv(name)) saved_ = old;
    had_ = std::getenv(name) != nullptr;
    ::setenv(name, value.c_str(), 1);
  }
  ~ScopedEnv() {
    if (had_) {
      ::setenv(name_, saved_.c_str(), 1);
    } else {
      ::unsetenv(name_);
    }
  }

 private:
  const char* name_;
  std::string saved_;
  bool had_ = false;
};

}  // namespace combabc::testing
