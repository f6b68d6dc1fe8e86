#pragma once
// What the history fuzzers run on a file: everything `combabc report` / `export` / `resume` read,
// through the read-only path, and then the export itself (CSV + JSON into the scratch
// directory), the first consumer of what was read. A combabc::Error is the expected outcome for a
// bad file; anything else is a finding (see fuzz_util.hpp).
#include <string>

#include "combabc/core/error.hpp"
#include "combabc/export/export.hpp"
#include "combabc/history/history_store.hpp"
#include "fuzz_util.hpp"

namespace combabc::fuzz {

inline void ReadHistory(const std::string& path) {
  try {
    const HistoryStore store = HistoryStore::Open(path, /*read_only=*/true);
    (void)store.LoadMetadata();
    (void)store.LoadHistory();
    (void)store.LoadResumePoint();
    ExportOptions options;
    options.overwrite = true;
    ExportRun(store, ScratchDir() + "/export", options);
  } catch (const Error&) {
    // Expected: not a history, corrupt, or a newer schema.
  }
}

}  // namespace combabc::fuzz
