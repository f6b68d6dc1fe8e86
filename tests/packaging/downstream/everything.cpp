// Links combabc::combabc from the installed package: opening a history reaches the calibration
// component and SQLite, which a static install must bring along.
#include <cstdio>

#include "combabc/history/history_store.hpp"

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  try {
    combabc::HistoryStore::Open(argv[1], /*read_only=*/true);
  } catch (const combabc::Error& e) {
    std::printf("%s\n", e.what());
    return e.kind() == combabc::ErrorKind::kNoInput ? 0 : 1;
  }
  return 1;  // the test names a history that does not exist
}
