#pragma once
// Error channel for bad user input and configuration (see docs/architecture.md).
// The algorithm's outcome goes in a Summary; broken invariants abort via COMBABC_CHECK.
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <string>
#include <string_view>
#include "combabc/core/enum_names.hpp"

namespace combabc {

// What went wrong, from the user's point of view. Each maps to a sysexits.h code so the CLI exits
// with the conventional status.
enum class ErrorKind {
  kUsage,       // 64: bad command line
  kData,        // 65: input data malformed (CSV, NaN, ...)
  kNoInput,     // 66: input file missing or unreadable
  kSoftware,    // 70: internal error, simulator crash
  kCantCreate,  // 73: cannot create an output file
  kIo,          // 74: I/O error while writing
  kConfig,      // 78: configuration invalid
};

int ExitCode(ErrorKind kind);
template <>
struct EnumNames<ErrorKind> {
  static constexpr std::pair<ErrorKind, const char*> kNames[] = {
      {ErrorKind::kUsage, "usage error"},
      {ErrorKind::kData, "data error"},
      {ErrorKind::kNoInput, "input error"},
      {ErrorKind::kSoftware, "internal error"},
      {ErrorKind::kCantCreate, "cannot create output"},
      {ErrorKind::kIo, "I/O error"},
      {ErrorKind::kConfig, "config error"},
  };
};

// `text` made safe to print on one terminal line: control characters (ANSI escapes, NUL, line
// breaks), C1 controls and bytes that are not valid UTF-8 become \n, \r, \t, \0 or \xNN; valid
// printable UTF-8 is kept. Cut (on a character boundary, marked "...") after `max_bytes`.
std::string Printable(std::string_view text,
                      std::size_t max_bytes = std::numeric_limits<std::size_t>::max());
// A short quoted excerpt of user input for a message: 'text', Printable and cut to 40 bytes, so
// an error never echoes more than a glimpse of a file (which may not even be the intended one).
std::string Excerpt(std::string_view text);

// A user-facing error. what() is one line: "file:line[:column]: field: message" with the parts
// that are known (a missing file has no line; an Options field has no file), made Printable and
// with the message cut to a few hundred bytes.
class Error : public std::runtime_error {
 public:
  Error(ErrorKind kind,
        std::string message,
        std::string file = {},
        int line = 0,
        std::string field = {},
        int column = 0);

  ErrorKind kind() const { return kind_; }
  const std::string& message() const { return message_; }
  const std::string& file() const { return file_; }
  int line() const { return line_; }
  const std::string& field() const { return field_; }
  int column() const { return column_; }  // 1-based CSV column, 0 when not applicable

 private:
  ErrorKind kind_;
  std::string message_;
  std::string file_;
  int line_;
  std::string field_;
  int column_;
};

}  // namespace combabc
