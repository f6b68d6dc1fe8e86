#include "combabc/core/error.hpp"

namespace combabc {
namespace {

std::string Format(const std::string& message,
                   const std::string& file,
                   int line,
                   const std::string& field) {
  std::string out;
  if (!file.empty()) {
    out += file;
    if (line > 0) {
      out += ':';
      out += std::to_string(line);
    }
    out += ": ";
  }
  if (!field.empty()) {
    out += field;
    out += ": ";
  }
  out += message;
  return out;
}

}  // namespace

int ExitCode(ErrorKind kind) {
  switch (kind) {
    case ErrorKind::kUsage:
      return 64;
    case ErrorKind::kData:
      return 65;
    case ErrorKind::kNoInput:
      return 66;
    case ErrorKind::kSoftware:
      return 70;
    case ErrorKind::kCantCreate:
      return 73;
    case ErrorKind::kIo:
      return 74;
    case ErrorKind::kConfig:
      return 78;
  }
  return 70;
}

Error::Error(ErrorKind kind, std::string message, std::string file, int line, std::string field)
    : std::runtime_error(Format(message, file, line, field)),
      kind_(kind),
      message_(std::move(message)),
      file_(std::move(file)),
      line_(line),
      field_(std::move(field)) {}

}  // namespace combabc
