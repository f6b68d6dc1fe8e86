// Writes a synthetic run history (36 clamps, 91-point curves by default) for trying the report
// and export tools without running the FE model:
//   combabc_fake_history OUT.db [--waves N] [--per-wave N] [--incomplete] [--no-curves]
//     [--reals N] [--multi-fidelity] [--pattern-classes] [--moves] [--config FILE]
// --config: the run's config text is FILE's (e.g. an example's), so that the answer places the
// sensor's clamps and the report draws the strip (or, for another simulator, does not).
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "combabc/core/error.hpp"
#include "history/fake_run.hpp"

int main(int argc, char** argv) {
  using namespace combabc;
  if (argc < 2) {
    std::fprintf(stderr,
                 "usage: %s OUT.db [--waves N] [--per-wave N] [--incomplete] [--no-curves] "
                 "[--reals N] [--multi-fidelity] [--pattern-classes] [--moves] [--config FILE]\n",
                 argv[0]);
    return 64;
  }
  testing::FakeRunOptions options;
  options.waves = 5;
  options.per_wave = 500;
  bool incomplete = false;
  std::string config;
  for (int i = 2; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--waves" && i + 1 < argc) {
      options.waves = std::atoi(argv[++i]);
    } else if (arg == "--per-wave" && i + 1 < argc) {
      options.per_wave = std::atoi(argv[++i]);
    } else if (arg == "--incomplete") {
      incomplete = true;
    } else if (arg == "--reals" && i + 1 < argc) {
      options.reals = std::atoi(argv[++i]);
    } else if (arg == "--multi-fidelity") {
      options.multi_fidelity = true;
    } else if (arg == "--moves") {
      options.moves = true;
    } else if (arg == "--pattern-classes") {
      options.pattern_classes = true;
    } else if (arg == "--config" && i + 1 < argc) {
      config = argv[++i];
    } else if (arg == "--no-curves") {
      options.outputs = false;
    } else {
      std::fprintf(stderr, "unknown argument: %s\n", arg.c_str());
      return 64;
    }
  }
  try {
    RunMetadata metadata = testing::MakeFakeMetadata(options);
    if (!config.empty()) {
      std::ifstream in(config);
      std::stringstream text;
      text << in.rdbuf();
      if (!in) {
        std::fprintf(stderr, "combabc_fake_history: cannot read %s\n", config.c_str());
        return 66;
      }
      metadata.config_text = text.str();
      metadata.config_path = config;
    }
    HistoryStore store = HistoryStore::Create(argv[1], metadata, /*overwrite=*/true);
    const RunHistory history = testing::MakeFakeHistory(options);
    const std::size_t n = history.waves.size();
    for (std::size_t t = 0; t < n; ++t) {
      // --incomplete: the last wave is cut after a third of its batches, as a killed run leaves it.
      const bool cut = incomplete && t + 1 == n;
      const std::int64_t batch = 100;
      const auto batches = static_cast<int>((history.waves[t].candidates + batch - 1) / batch);
      testing::RecordWave(store, history.waves[t], batch, cut ? batches / 3 : -1);
    }
    if (!incomplete) store.Finish(history.summary);
  } catch (const Error& error) {
    std::fprintf(stderr, "combabc_fake_history: %s\n", error.what());
    return ExitCode(error.kind());
  }
  return 0;
}
