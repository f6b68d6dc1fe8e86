#pragma once
// The text of numbers and strings in the export's files (CSV and JSON), shared by export.cpp,
// answer.cpp and fit_checks.cpp, so that summary.json has one spelling of a number. Private to
// src/export.
#include <charconv>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace combabc::export_text {

// Shortest text that reads back to the same double; Inf / -Inf / NaN as pandas and MATLAB read
// them.
inline std::string Number(double value) {
  if (std::isnan(value)) return "NaN";
  if (std::isinf(value)) return value > 0 ? "Inf" : "-Inf";
  char text[32];
  const auto result = std::to_chars(text, text + sizeof text, value);
  return std::string(text, result.ptr);
}

inline std::string JsonNumber(double value) {
  return std::isfinite(value) ? Number(value) : "null";
}

inline std::string JsonString(const std::string& text) {
  std::string out = "\"";
  for (char c : text) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\r':
        out += "\\r";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char escaped[8];
          std::snprintf(escaped, sizeof escaped, "\\u%04x", static_cast<unsigned>(c));
          out += escaped;
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

inline std::string JsonArray(const std::vector<double>& values) {
  std::string out = "[";
  for (std::size_t i = 0; i < values.size(); ++i) out += (i ? "," : "") + JsonNumber(values[i]);
  return out + "]";
}

}  // namespace combabc::export_text
