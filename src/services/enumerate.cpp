#include "combabc/services/enumerate.hpp"

#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <optional>
#include <ostream>

#include "combabc/config/config.hpp"
#include "combabc/core/error.hpp"
#include "combabc/core/output_files.hpp"
#include "combabc/history/history_store.hpp"
#include "combabc/samplers/enumeration.hpp"
#include "combabc/services/report.hpp"
#include "services/steps/output_folders.hpp"
#include "services/steps/problem.hpp"
#include "services/steps/read_back.hpp"
#include "services/steps/report_checks.hpp"
#include "services/steps/worker_steps.hpp"

namespace combabc::services {
namespace fs = std::filesystem;
namespace {

// The thresholds an enumeration uses by default: where the config's run would end.
std::vector<double> FinalThresholds(const CalibrationConfig& config) {
  std::vector<double> eps;
  for (std::size_t s = 0; s < config.smc.thresholds.size(); ++s) {
    if (const std::optional<double> end = FinalThreshold(config.smc.thresholds[s])) {
      eps.push_back(*end);
    } else {
      throw Error(ErrorKind::kUsage,
                  "threshold component " + std::to_string(s + 1) +
                      " has no final threshold in the config (an adaptive schedule without "
                      "target); give one per threshold component with --threshold",
                  config.path);
    }
  }
  return eps;
}

std::string Num(double x) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", x);
  return b;
}

std::string BitString(const std::vector<std::uint8_t>& bits) {
  std::string s;
  for (std::uint8_t b : bits) s += b ? '1' : '0';
  return s;
}

// RFC 4180 quoting, only when needed.
std::string Field(const std::string& text) {
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string q = "\"";
  for (char c : text) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

void WriteEnumerationFiles(OutputDirectory& dir, const RunMetadata& m, const EnumerationResult& r) {
  const std::size_t d = m.bit_names.size();
  std::ostream& corr = dir.Add("pair_correlations.csv");
  // A bit constant under the posterior has no correlation: written as 0 (docs/algorithm.md).
  corr << "bit";
  for (const std::string& name : m.bit_names) corr << ',' << Field(name);
  corr << '\n';
  for (std::size_t i = 0; i < d && !r.correlations.empty(); ++i) {
    corr << Field(m.bit_names[i]);
    for (std::size_t j = 0; j < d; ++j) corr << ',' << Num(r.correlations[i * d + j]);
    corr << '\n';
  }
  std::ostream& top = dir.Add("top_configurations.csv");
  top << "rank,configuration,bits,prior,posterior";
  for (const DistanceComponent& c : m.distance_components) top << ',' << Field("d_" + c.name);
  top << '\n';
  for (std::size_t k = 0; k < r.top.size(); ++k) {
    const Particle& p = r.top[k];
    top << k + 1 << ',' << p.index << ',' << BitString(p.theta.bits) << ','
        << Num(std::exp(p.log_weight)) << ',' << Num(p.weight);
    for (double x : p.distance) top << ',' << Num(x);
    top << '\n';
  }
  std::ostream& marginals = dir.Add("marginals.csv");
  marginals << "bit,name,prior,posterior\n";
  for (std::size_t k = 0; k < d && !r.marginals.empty(); ++k) {
    marginals << k + 1 << ',' << Field(m.bit_names[k]) << ',' << Num(m.bit_prior_one[k]) << ','
              << Num(r.marginals[k]) << '\n';
  }
}

// Where the enumeration writes its history (and beside it its tables and report): -o DIR as given,
// else the folder enumeration/ inside the config's [output] directory, so that it never meets the
// history and report of `combabc run` on the same config.
std::string EnumerationDirectory(const EnumerateRequest& request, const Problem& p) {
  if (!request.output_directory.empty()) return request.output_directory;
  return (fs::path(ResolvePath(p.config.directory, p.config.output.directory)) / kEnumerationFolder)
      .string();
}

// The tables beside the history: <stem>.enumeration/.
std::string TablesDirectory(const fs::path& history) {
  return (history.parent_path() / (history.stem().string() + ".enumeration")).string();
}

// Enumeration visits 2^(free bits) configurations; beyond kMaxEnumerationBits that is refused
// at the config key that sets the bits, before the model is built (Enumerate checks it again for
// library callers, without a file to name).
void CheckEnumerable(const CalibrationConfig& c) {
  const int free = BinarySpace(c.space).num_free();
  if (free <= kMaxEnumerationBits) return;
  const std::string bits = std::to_string(c.space.dimension);
  throw Error(ErrorKind::kConfig,
              "gives " + bits + " bits, " + std::to_string(free) + " free after ties (2^" +
                  std::to_string(free) + " configurations); enumerate takes at most 2^" +
                  std::to_string(kMaxEnumerationBits) +
                  ": tie bits ([sampler] tie, e.g. left/right clamp pairs) to reduce them, or run "
                  "combinatorial ABC-SMC (combabc run)",
              c.path,
              c.bits_line,
              c.bits_key);
}

// The enumeration's history, tables and report (after the checks RunEnumeration made).
void WriteEnumeration(const EnumerateRequest& request,
                      const Problem& p,
                      const EnumerationOptions& options,
                      const EnumerationResult& result,
                      EnumerateOutcome& outcome) {
  const fs::path history = fs::path(EnumerationDirectory(request, p)) / p.config.output.database;
  const std::string files_directory = TablesDirectory(history);
  RunMetadata metadata = Describe(p);
  // The stored particles carry exact posterior masses, so both marginals are the exact ones; the
  // importance estimator is the one whose weights they are (termination "enumerated" tells).
  metadata.estimator = ToString(Estimator::kImportance);
  auto store = HistoryStore::Create(history.string(), metadata, request.overwrite);
  outcome.history_path = store.path();
  const WaveRecord wave = result.Wave(options.thresholds, p.space->binary().free_prior_one());
  RunSummary summary;
  summary.termination = Termination::kEnumerated;
  summary.message = "exact enumeration of " + std::to_string(result.configurations) +
                    " configurations: " + std::to_string(result.accepted) + " accepted, evidence " +
                    Num(result.evidence);
  summary.waves_completed = 1;
  summary.simulations = result.enumerated;
  summary.wall_seconds = result.wall_seconds;
  try {
    store.OnWaveStart(wave);
    const BatchProgress done{0,
                             result.enumerated,
                             static_cast<std::int64_t>(wave.particles.size()),
                             0,
                             static_cast<int>(wave.particles.size()),
                             result.enumerated,
                             result.wall_seconds,
                             0,
                             {},
                             std::nullopt};
    store.OnBatch(done, wave.particles);
    store.OnWaveEnd(wave);
    store.Finish(summary);
  } catch (const std::exception& e) {
    try {
      store.MarkFailed(e.what());
    } catch (const std::exception&) {
      // The store itself may be what failed (disk full); the first error is the one to report.
    }
    throw;
  }
  // As run's: from the history as stored.
  ReadBack back = ReadBackHistory(store);
  outcome.checks = std::move(back.checks);
  outcome.answer = std::move(back.answer);
  outcome.strip = std::move(back.strip);
  OutputDirectory files(files_directory, request.overwrite);
  WriteEnumerationFiles(files, metadata, result);
  files.Commit();
  outcome.enumeration_directory = files_directory;
  if (request.report) {
    try {
      outcome.report_directory = WriteReport(
          store.path(), ReportDirectory(store.path()), false, request.on_report_progress);
    } catch (const Error& e) {
      throw Error(e.kind(),
                  "the enumeration is saved in " + store.path() +
                      " ('combabc report' retries the report), but its report failed: " + e.what());
    }
  }
}

}  // namespace

EnumerateOutcome RunEnumeration(const EnumerateRequest& request, SmcObserver* progress) {
  OutputFolders folders;  // kept once the enumeration's results are written
  Problem p;
  LoadProblem(request.config_path, request.threads, p, request.config_text);
  CheckEnumerable(p.config);
  // The exact posterior is the expensive simulator's: a cheap one ([simulator.low_fidelity]) is
  // neither built nor used.
  EnumerateOutcome outcome;
  outcome.low_fidelity_ignored = p.config.low_fidelity.has_value();
  p.config.low_fidelity.reset();
  MakeExecutor(p, request.executor);
  Executor& executor = *p.executor;

  if (!request.thresholds.empty()) {
    // One per threshold component, in the distance vector's order: name them.
    std::string names;
    std::size_t count = 0;
    for (const DistanceComponent& c : p.distance->components()) {
      if (c.kind != ComponentKind::kThreshold) continue;
      names += (count++ ? ", " : "") + c.name;
    }
    if (request.thresholds.size() != count) {
      throw Error(ErrorKind::kUsage,
                  "gives " + std::to_string(request.thresholds.size()) + " thresholds; give " +
                      std::to_string(count) +
                      ", one per threshold component in this order: " + names,
                  "",
                  0,
                  "--threshold");
    }
  }
  EnumerationOptions options;
  options.thresholds = request.thresholds.empty() ? FinalThresholds(p.config) : request.thresholds;
  options.threads = p.config.smc.threads;
  options.top = request.top;
  options.max_particles = request.max_particles;
  options.keep_outputs = p.config.smc.keep_outputs;
  options.seed = p.config.smc.seed;

  const std::string directory = EnumerationDirectory(request, p);
  const fs::path history = fs::path(directory) / p.config.output.database;
  const std::string files_directory = TablesDirectory(history);
  // Everything that would refuse the results at the end is refused now, before hours of work.
  OnPrimary(executor, [&] {
    std::error_code ec;
    if (!request.overwrite && fs::exists(fs::symlink_status(history, ec))) {
      throw Error(ErrorKind::kCantCreate,
                  "an enumeration's history already exists there (use --overwrite to replace it, "
                  "or -o DIR to enumerate into another folder)",
                  history.string());
    }
    if (request.report) CheckReportPossible(ReportDirectory(history.string()));
    folders.Create(directory);
    OutputDirectory::Check(files_directory, request.overwrite);
  });
  BuildModelIn(p, history.string());

  const EnumerationResult result = Enumerate(p.view(), options, progress);
  outcome.configurations = result.configurations;
  outcome.enumerated = result.enumerated;
  outcome.accepted = result.accepted;
  outcome.evidence = result.evidence;
  // The heaviest configuration's log mass over its share: exact where the evidence underflows.
  if (!result.top.empty() && result.top.front().weight > 0.0) {
    outcome.log_evidence = result.top.front().log_weight - std::log(result.top.front().weight);
  }
  outcome.wall_seconds = result.wall_seconds;
  outcome.interrupted = result.interrupted;
  if (result.interrupted) return outcome;
  // The files, on the primary only.
  OnPrimary(executor, [&] {
    WriteEnumeration(request, p, options, result, outcome);
    folders.Keep();
  });
  return outcome;
}

}  // namespace combabc::services
