#include "combabc/core/error.hpp"

#include <cstdint>

namespace combabc {
namespace {

// Caps keep every message one short line whatever the input: a path or key is rarely longer than
// a few hundred bytes, and a message never needs to quote more than an excerpt.
constexpr std::size_t kMaxPathBytes = 512;
constexpr std::size_t kMaxFieldBytes = 200;
constexpr std::size_t kMaxMessageBytes = 400;
constexpr std::size_t kExcerptBytes = 40;

// Length of the valid UTF-8 sequence starting at text[i] that encodes a printable character
// (not a C0/C1 control, not DEL), or 0.
std::size_t PrintableSequence(std::string_view text, std::size_t i) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char lead = byte(i);
  if (lead >= 0x20 && lead < 0x7f) return 1;
  std::size_t length = 0;
  std::uint32_t code = 0;
  if (lead >= 0xc2 && lead <= 0xdf) {
    length = 2;
    code = lead & 0x1fu;
  } else if (lead >= 0xe0 && lead <= 0xef) {
    length = 3;
    code = lead & 0x0fu;
  } else if (lead >= 0xf0 && lead <= 0xf4) {
    length = 4;
    code = lead & 0x07u;
  } else {
    return 0;
  }
  if (i + length > text.size()) return 0;
  for (std::size_t k = 1; k < length; ++k) {
    if ((byte(i + k) & 0xc0u) != 0x80u) return 0;
    code = (code << 6) | (byte(i + k) & 0x3fu);
  }
  const std::uint32_t smallest[] = {0, 0, 0x80, 0x800, 0x10000};
  if (code < smallest[length] || code > 0x10ffff) return 0;  // overlong or out of range
  if (code >= 0xd800 && code <= 0xdfff) return 0;            // surrogate
  if (code >= 0x80 && code <= 0x9f) return 0;                // C1 control
  return length;
}

std::string Format(const std::string& message,
                   const std::string& file,
                   int line,
                   int column,
                   const std::string& field) {
  std::string out;
  if (!file.empty()) {
    out += Printable(file, kMaxPathBytes);
    if (line > 0) {
      out += ':';
      out += std::to_string(line);
      if (column > 0) {
        out += ':';
        out += std::to_string(column);
      }
    }
    out += ": ";
  }
  if (!field.empty()) {
    out += Printable(field, kMaxFieldBytes);
    out += ": ";
  }
  out += Printable(message, kMaxMessageBytes);
  return out;
}

}  // namespace

std::string Printable(std::string_view text, std::size_t max_bytes) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  for (std::size_t i = 0; i < text.size();) {
    std::string piece;
    if (const std::size_t n = PrintableSequence(text, i); n > 0) {
      piece.assign(text.substr(i, n));
      i += n;
    } else {
      const auto c = static_cast<unsigned char>(text[i++]);
      switch (c) {
        case '\n':
          piece = "\\n";
          break;
        case '\r':
          piece = "\\r";
          break;
        case '\t':
          piece = "\\t";
          break;
        case '\0':
          piece = "\\0";
          break;
        default:
          piece = {'\\', 'x', kHex[c >> 4], kHex[c & 0xf]};
      }
    }
    if (out.size() + piece.size() > max_bytes) {
      out += "...";
      break;
    }
    out += piece;
  }
  return out;
}

std::string Excerpt(std::string_view text) { return "'" + Printable(text, kExcerptBytes) + "'"; }

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

Error::Error(
    ErrorKind kind, std::string message, std::string file, int line, std::string field, int column)
    : std::runtime_error(Format(message, file, line, column, field)),
      kind_(kind),
      message_(std::move(message)),
      file_(std::move(file)),
      line_(line),
      field_(std::move(field)),
      column_(column) {}

}  // namespace combabc
