#pragma once
// A tiny but complete run history, written by the library itself (HistoryStore::Create and the
// SmcObserver callbacks), for the history fuzzers: 6 bits, two distance components, 4-point
// curves, wave 1 ended and complete, wave 2 cut short after one batch (status "running"), so that
// the readers' every path (complete waves, the partial wave, derived statistics) has data.
// It is compacted to 512-byte pages in rollback-journal mode, so it is a few KB and one file.
#include <string>

namespace combabc::fuzz {

// Writes the history to `path` (replacing it). Throws combabc::Error if the library cannot.
void WriteSeedHistory(const std::string& path);

}  // namespace combabc::fuzz
