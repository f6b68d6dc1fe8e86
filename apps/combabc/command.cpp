#include "command.hpp"

#include <unistd.h>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <iostream>
#include <limits>
#include <sstream>
#include <string>

#include "combabc/config/config.hpp"
#include "combabc/core/error.hpp"
#include "combabc/export/answer.hpp"
#include "combabc/export/strip.hpp"
#include "combabc/history/history_store.hpp"
#include "interrupt.hpp"
#include "progress_display.hpp"

namespace combabc::cli {
namespace {

// Whether the terminal's last line is ReportProgressLine's, not yet ended: an error clears it
// first, so that the error is a line of its own. The CLI's one thread writes and reads it.
bool report_line_open = false;

void ClearReportLine() {
  if (report_line_open) std::cerr << "\r\033[K";
  report_line_open = false;
}

}  // namespace

void AddNoCacheFlag(CLI::App& command) {
  command.add_flag_callback(
      "--no-cache",
      [] { ::setenv("COMBABC_CACHE_DIR", "", 1); },
      "Build the sensor's precomputed pieces afresh, without the disk cache");
}

int Guarded(const Session& session, bool quiet, const std::function<int(SmcObserver*)>& job) {
  return Guarded(session, quiet, {}, job);
}

int Guarded(const Session& session,
            bool quiet,
            const std::vector<bool>& temperatures,
            const std::function<int(SmcObserver*)>& job) {
  ProgressDisplay progress(session.primary() && isatty(STDERR_FILENO) != 0, temperatures);
  InterruptObserver interrupt(quiet || !session.primary() ? nullptr : &progress);
  try {
    return job(&interrupt);
  } catch (const Error& e) {
    progress.Clear();
    ClearReportLine();
    std::cerr << "combabc: " << ToString(e.kind()) << ": " << e.what() << "\n";
    return ExitCode(e.kind());
  } catch (const std::exception& e) {
    progress.Clear();
    ClearReportLine();
    std::cerr << "combabc: internal error: " << Printable(e.what(), 400) << "\n";
    return kExitSoftware;
  }
}

void PrintAnswer(const Session& session,
                 bool quiet,
                 const std::optional<Answer>& answer,
                 const std::optional<StripLayout>& strip) {
  if (quiet || !session.primary()) return;
  if (answer) {
    const std::string picture =
        strip ? StripText(*answer, *strip, TerminalStyle(STDOUT_FILENO)) : "";
    std::cout << "\n" << picture << (picture.empty() ? "" : "\n") << AnswerText(*answer);
  } else {
    std::cerr << "combabc: the answer could not be read back (see the checks above)\n";
  }
}

std::vector<bool> TemperatureSlotsOfConfig(const std::string& config_path) {
  std::vector<bool> slots;
  try {
    for (const ExperimentConfig& x : LoadConfig(config_path).experiments) {
      for (const MetricComponentConfig& c : x.metric.components) {
        const ComponentKind kind = KindOf(c);
        if (kind != ComponentKind::kIndicator) {
          slots.push_back(kind == ComponentKind::kNegLogLikelihood);
        }
      }
    }
  } catch (const Error&) {
    return {};
  }
  return slots;
}

std::vector<bool> TemperatureSlotsOfHistory(const std::string& history_path) {
  std::vector<bool> slots;
  try {
    const RunMetadata m = HistoryStore::Open(history_path, /*read_only=*/true).LoadMetadata();
    for (const DistanceComponent& c : m.distance_components) {
      if (c.kind != ComponentKind::kIndicator) {
        slots.push_back(c.kind == ComponentKind::kNegLogLikelihood);
      }
    }
  } catch (const Error&) {
    return {};
  }
  return slots;
}

services::ReportProgress ReportProgressLine(const Session& session, bool quiet, bool off_terminal) {
  const bool terminal = isatty(STDERR_FILENO) != 0;
  if (quiet || !session.primary() || (!terminal && !off_terminal)) return {};
  return [terminal](int done, int total) {
    if (!terminal) {
      if (total == 0) std::cerr << "writing report ...\n" << std::flush;
      return;
    }
    std::cerr << "\r\033[Kwriting report ...";
    if (total > 0) std::cerr << " " << done << "/" << total << " figures";
    // Left open until the last figure; an error meanwhile clears it (Guarded).
    report_line_open = done < total || total == 0;
    std::cerr << (report_line_open ? "" : "\n") << std::flush;
  };
}

int PrimaryOnly(const Session& session, const std::function<int()>& job) {
  return Guarded(session, false, [&](SmcObserver*) { return session.primary() ? job() : 0; });
}

CLI::Validator NonNegativeInteger() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        std::int64_t value = 0;
        const char* end = text.data() + text.size();
        const auto [at, error] = std::from_chars(text.data(), end, value);
        if (text.empty() || error != std::errc() || at != end || value < 0) {
          return "must be a whole number from 0 to " +
                 std::to_string(std::numeric_limits<std::int64_t>::max()) + ", not '" + text + "'";
        }
        return {};
      },
      "INT >= 0");
}

CLI::Validator RealIn(double low, double high) {
  return CLI::Validator(
      [low, high](std::string& text) -> std::string {
        char* end = nullptr;
        const double value = std::strtod(text.c_str(), &end);
        const bool parsed = !text.empty() && end == text.c_str() + text.size();
        if (!parsed || std::isnan(value) || value < low || value > high) {
          std::ostringstream message;
          message << "must be a number ";
          if (std::isinf(high)) {
            message << ">= " << low;
          } else if (high == std::numeric_limits<double>::max()) {
            message << ">= " << low << ", finite";
          } else {
            message << "in [" << low << ", " << high << "]";
          }
          message << ", not '" << text << "'";
          return message.str();
        }
        return {};
      },
      "NUMBER");
}

}  // namespace combabc::cli
