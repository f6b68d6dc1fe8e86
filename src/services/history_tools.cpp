// The history tools: verify a history, export it (CSV, JSON and the NetCDF file).
#include "combabc/services/history_tools.hpp"

#include <filesystem>
#include <string_view>

#include "combabc/config/config.hpp"
#include "combabc/core/error.hpp"
#include "combabc/core/output_files.hpp"
#include "combabc/export/answer.hpp"
#include "combabc/export/export.hpp"
#include "combabc/history/history_store.hpp"
#include "services/adapters/python_script.hpp"
#include "services/design_campaign.hpp"
#include "services/steps/read_back.hpp"

namespace combabc::services {
namespace fs = std::filesystem;
namespace {

std::string Sibling(const std::string& history_path, const std::string& name) {
  const auto parent = fs::path(history_path).parent_path();
  return (parent.empty() ? fs::path(name) : parent / name).string();
}

constexpr const char* kNetcdfFile = "inference_data.nc";
constexpr const char* kNetcdfNeeds =
    "the NetCDF file needs Python 3 with xarray and netCDF4 (Debian: apt-get install "
    "python3-xarray python3-netcdf4), or COMBABC_PYTHON naming such a python";

// inference_data.nc (ArviZ's InferenceData layout, docs/history.md) made by
// scripts/report/combabc_netcdf.py from the staged CSV and JSON files, so that its values are
// theirs. Without the script's Python packages the export goes on without it and says why in
// outcome.note; any other failure of the script fails the export (nothing is written).
// all_waves: also every wave's resampled posterior (--all-waves).
void AddNetcdf(OutputDirectory& dir, bool all_waves, ExportOutcome& outcome) {
  PythonScript tools;
  try {
    tools = FindPythonScript("combabc_netcdf.py", "COMBABC_NETCDF_SCRIPT", kNetcdfNeeds);
  } catch (const Error& e) {
    outcome.note = std::string("no ") + kNetcdfFile + ": " + e.what();
    return;
  }
  dir.Add(kNetcdfFile);
  std::vector<std::string> args = {tools.python,
                                   tools.script,
                                   "--particles",
                                   dir.StagedPath("particles.csv"),
                                   "--measured",
                                   dir.StagedPath("measured.csv"),
                                   "--summary",
                                   dir.StagedPath("summary.json"),
                                   "--out",
                                   dir.StagedPath(kNetcdfFile),
                                   "--positions",
                                   dir.StagedPath("positions.csv")};
  // The posterior predictive group needs the curves, written when the run kept its outputs.
  if (dir.Has("curves.csv")) {
    args.insert(args.end(), {"--curves", dir.StagedPath("curves.csv")});
  }
  if (all_waves) args.emplace_back("--all-waves");
  const ProcessResult result = RunProcess(args, kNetcdfNeeds);
  constexpr int kUnavailable = 69;  // EX_UNAVAILABLE: xarray or netCDF4 missing
  if (result.status == kUnavailable) {
    dir.Discard(kNetcdfFile);
    outcome.note = std::string("no ") + kNetcdfFile + ": " +
                   ScriptMessage(result.err, result.status, "combabc_netcdf");
    return;
  }
  if (result.status != 0) {
    throw Error(KindOfScriptStatus(result.status),
                std::string(kNetcdfFile) + ": " +
                    ScriptMessage(result.err, result.status, "combabc_netcdf"));
  }
  outcome.netcdf_path = (fs::path(dir.path()) / kNetcdfFile).string();
  // A file without a posterior group (signed multi-fidelity weights): the script's note line,
  // for the terminal.
  constexpr std::string_view kNote = "combabc_netcdf: note: ";
  const std::size_t at = result.err.find(kNote);
  if (at != std::string::npos) {
    const std::size_t from = at + kNote.size();
    outcome.note = std::string(kNetcdfFile) + ": " +
                   result.err.substr(from, result.err.find('\n', from) - from);
  }
}

}  // namespace

Answer ReadAnswer(const std::string& history_path) {
  const HistoryStore store = HistoryStore::Open(history_path, /*read_only=*/true);
  const RunMetadata metadata = store.LoadMetadata();
  return SummariseAnswer(metadata, store.LoadHistory(), BitPositions(metadata));
}

VerifyOutcome VerifyHistory(const std::string& history_path) {
  const HistoryCheck check = HistoryStore::Verify(history_path);
  VerifyOutcome outcome;
  outcome.ok = check.problems.empty();
  if (!outcome.ok) {
    outcome.lines = check.problems;
    return outcome;
  }
  const std::string waves = std::to_string(check.waves) + (check.waves == 1 ? " wave" : " waves");
  outcome.lines.push_back(history_path + ": OK (" + waves +
                          (check.checksummed
                               ? ", checksums verified)"
                               : "; no checksums (schema v" + std::to_string(check.schema_version) +
                                     "): structure checked only)"));
  // The limits the run ran under, where a resume changed the config's (docs/history.md).
  const RunMetadata metadata = HistoryStore::Open(history_path, true).LoadMetadata();
  std::string limits;
  for (const auto& [key, value] : metadata.stop_limits) {
    if (!limits.empty()) limits += ", ";
    limits.append(key).append(" = ").append(value);
  }
  if (!limits.empty()) outcome.lines.back() += "; stop limits set on resume: " + limits;
  return outcome;
}

ExportOutcome ExportHistory(const std::string& history_path,
                            const std::string& directory,
                            bool overwrite,
                            bool netcdf,
                            bool all_waves) {
  ExportOutcome outcome;
  outcome.directory = directory.empty() ? Sibling(history_path, "export") : directory;
  ExportOptions options;
  options.overwrite = overwrite;
  if (netcdf) {
    options.add_files = [&](OutputDirectory& dir) { AddNetcdf(dir, all_waves, outcome); };
  }
  const HistoryStore store = HistoryStore::Open(history_path, /*read_only=*/true);
  const RunMetadata metadata = store.LoadMetadata();
  options.bit_positions = BitPositions(metadata);
  options.strip = StripOf(metadata);
  options.checks = CheckOptions(metadata);
  // A joint run of the sensor: which experiment decided which clamp (simulates the truths'
  // neighbourhoods). Where it cannot be had, the rest is exported and the note says why.
  std::string why_not;
  options.campaign = RunCampaignView(history_path, &why_not);
  ExportRun(store, outcome.directory, options);
  if (!why_not.empty()) {
    outcome.note += (outcome.note.empty() ? "" : "; ") + std::string("no campaign.csv: ") + why_not;
  }
  return outcome;
}

}  // namespace combabc::services
