// Writes the history fuzzers' seed (history_seed.hpp) to the path given:
//   build-fuzz/fuzz/combabc_make_history_seed fuzz/corpus/history/seed.sqlite
// scripts/fuzz.sh does not run it: the seed is committed, and regenerated only when the schema
// changes (docs/fuzzing.md).
#include <cstdio>

#include "combabc/core/error.hpp"
#include "history_seed.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s OUT.sqlite\n", argv[0]);
    return 64;
  }
  try {
    combabc::fuzz::WriteSeedHistory(argv[1]);
  } catch (const combabc::Error& error) {
    std::fprintf(stderr, "combabc_make_history_seed: %s\n", error.what());
    return combabc::ExitCode(error.kind());
  }
  return 0;
}
