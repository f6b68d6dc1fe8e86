#pragma once
// `combabc report`: a run's figures and index.html.
//
// ReportProgress: (0, 0) when the report starts (its export is staged first), then (done, total)
// each time the script has drawn a figure. It runs on the calling thread.
#include <functional>
#include <string>

namespace combabc::services {

// Figures (in the formats of the run's [output] figures) and index.html for a run, into
// `directory` (default: report/ beside the history). The history is read once, by the export:
// the run's export (ExportRun) is staged in a private folder under $TMPDIR, and
// scripts/report/combabc_report.py, run with $COMBABC_PYTHON (default /usr/bin/python3), draws
// from it into a second private folder; the script is the install's share/combabc/report/
// (relative to the binary, core/install_paths.hpp) unless $COMBABC_REPORT_SCRIPT names one. What
// it drew is then published into the directory under OutputDirectory's rules
// (core/output_files.hpp): a previous report there is replaced, a non-empty directory combabc did
// not write is refused (before any work) unless `overwrite`. A failure is one combabc::Error line
// and leaves the directory as it was. Returns the directory. `progress`, when set, hears how far
// the drawing is (the CLI's "writing report" line).
using ReportProgress = std::function<void(int done, int total)>;
std::string WriteReport(const std::string& history_path,
                        const std::string& directory = {},
                        bool overwrite = false,
                        const ReportProgress& progress = {});

}  // namespace combabc::services
