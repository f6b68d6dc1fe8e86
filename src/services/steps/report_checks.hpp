#pragma once
// What run, resume and enumerate need of the report before they start (src/services/report.cpp).
#include <string>

namespace combabc::services {

// report/ beside the history: where run and resume write the report.
std::string ReportDirectory(const std::string& history_path);

// Throws the error the report would end with, if it can already be known: no Python or no
// script, a Python without numpy or matplotlib, or a `directory` that exists with files combabc
// did not write. Changes nothing, so a run learns before it starts (not after hours) that its
// report would be refused.
void CheckReportPossible(const std::string& directory);

}  // namespace combabc::services
