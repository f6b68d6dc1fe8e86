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

#include "combabc/core/error.hpp"
#include "combabc/export/answer.hpp"
#include "interrupt.hpp"
#include "progress_display.hpp"

namespace combabc::cli {

void AddNoCacheFlag(CLI::App& command) {
  command.add_flag_callback(
      "--no-cache",
      [] { ::setenv("COMBABC_CACHE_DIR", "", 1); },
      "Build the sensor's precomputed pieces afresh, without the disk cache");
}

int Guarded(const Session& session, bool quiet, const std::function<int(SmcObserver*)>& job) {
  ProgressDisplay progress(session.primary() && isatty(STDERR_FILENO) != 0);
  InterruptObserver interrupt(quiet || !session.primary() ? nullptr : &progress);
  try {
    return job(&interrupt);
  } catch (const Error& e) {
    progress.Clear();
    std::cerr << "combabc: " << ToString(e.kind()) << ": " << e.what() << "\n";
    return ExitCode(e.kind());
  } catch (const std::exception& e) {
    progress.Clear();
    std::cerr << "combabc: internal error: " << Printable(e.what(), 400) << "\n";
    return kExitSoftware;
  }
}

void PrintAnswer(const Session& session, bool quiet, const std::optional<Answer>& answer) {
  if (quiet || !session.primary()) return;
  if (answer) {
    std::cout << "\n" << AnswerText(*answer);
  } else {
    std::cerr << "combabc: the answer could not be read back (see the checks above)\n";
  }
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
