// libFuzzer target: the run-history reader on raw file bytes. The bytes are written to a
// .sqlite file in a private scratch directory, which is opened read-only and read back in full
// (Open + LoadMetadata + LoadHistory + LoadResumePoint). Mutating a real SQLite file byte by byte
// mostly breaks SQLite's own checks, so the seed (fuzz/corpus/history/seed.sqlite, made by the
// library: history_seed.hpp) is tiny, and history_patch_fuzzer complements this target by
// changing the history's *values* through SQL instead. A combabc::Error is the expected outcome;
// anything else is a finding (see fuzz_util.hpp).
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_util.hpp"
#include "history_readers.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = combabc::fuzz::ScratchDir() + "/RUN.sqlite";
  combabc::fuzz::RemoveDatabase(path);  // no -wal / -journal of the last input may be replayed
  combabc::fuzz::WriteFile(path, data, size);
  combabc::fuzz::ReadHistory(path);
  return 0;
}
