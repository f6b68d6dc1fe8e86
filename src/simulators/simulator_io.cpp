#include "simulator_io.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>

#include "combabc/core/error.hpp"

namespace combabc::simulators_internal {
namespace {

std::string CsvField(const std::string& text) {
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string q = "\"";
  for (char c : text) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

std::string JsonString(const std::string& text) {
  std::string q = "\"";
  for (unsigned char c : text) {
    if (c == '"' || c == '\\') {
      q += '\\';
      q += static_cast<char>(c);
    } else if (c < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      q += buf;
    } else {
      q += static_cast<char>(c);
    }
  }
  return q + "\"";
}

// Collects numbers, checking count, NaN and infinities; `line` names where each came from.
class Collector {
 public:
  explicit Collector(std::span<double> out) : out_(out) {}
  // Parses `token` (non-empty); returns the reason it was refused, or empty.
  std::string Add(std::string_view token, int line) {
    double v = 0.0;
    const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), v);
    const bool nan_text = token == "nan" || token == "NaN" || token == "-nan";
    if (!nan_text && (ec != std::errc() || end != token.data() + token.size())) {
      return Where(line) + Excerpt(token) + " is not a number";
    }
    if (nan_text || std::isnan(v)) {
      return "output value " + std::to_string(count_ + 1) + " is NaN" + InLine(line);
    }
    if (!std::isfinite(v)) {
      return "output value " + std::to_string(count_ + 1) + " is infinite" + InLine(line);
    }
    if (count_ < out_.size()) out_[count_] = v;
    ++count_;
    return {};
  }
  std::string Finish() const {
    if (count_ == out_.size()) return {};
    return "returned " + std::to_string(count_) + " values; expected " +
           std::to_string(out_.size());
  }

 private:
  static std::string Where(int line) {
    return line <= 0 ? "" : "line " + std::to_string(line) + ": ";
  }
  static std::string InLine(int line) {
    return line <= 0 ? "" : " (line " + std::to_string(line) + ")";
  }
  std::span<double> out_;
  std::size_t count_ = 0;
};

bool IsSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

std::string ReadCsv(std::string_view text, std::span<double> out) {
  Collector values(out);
  int line = 1;
  std::size_t i = 0;
  while (i < text.size()) {
    const char c = text[i];
    if (c == '\n') ++line;
    if (IsSpace(c) || c == ',') {
      ++i;
      continue;
    }
    std::size_t j = i;
    while (j < text.size() && !IsSpace(text[j]) && text[j] != ',') ++j;
    if (std::string reason = values.Add(text.substr(i, j - i), line); !reason.empty()) {
      return reason;
    }
    i = j;
  }
  return values.Finish();
}

std::string ReadJson(std::string_view text, std::span<double> out) {
  Collector values(out);
  int line = 1;
  std::size_t i = 0;
  auto skip = [&] {
    while (i < text.size() && IsSpace(text[i])) {
      if (text[i] == '\n') ++line;
      ++i;
    }
  };
  auto expected = [&](const char* what) {
    const std::string_view rest = text.substr(i, std::min<std::size_t>(12, text.size() - i));
    return "line " + std::to_string(line) + ": expected " + what +
           (i < text.size() ? ", got " + Excerpt(rest) : ", got the end of the output");
  };
  skip();
  if (i >= text.size() || text[i] != '[') return expected("a JSON array of numbers '['");
  ++i;
  skip();
  if (i < text.size() && text[i] == ']') {
    ++i;
  } else {
    for (;;) {
      skip();
      std::size_t j = i;
      while (j < text.size() && !IsSpace(text[j]) && text[j] != ',' && text[j] != ']') ++j;
      if (j == i) return expected("a number");
      const std::string_view token = text.substr(i, j - i);
      if (token == "null") return "line " + std::to_string(line) + ": null is not a number";
      if (std::string reason = values.Add(token, line); !reason.empty()) return reason;
      i = j;
      skip();
      if (i < text.size() && text[i] == ',') {
        ++i;
        continue;
      }
      if (i < text.size() && text[i] == ']') {
        ++i;
        break;
      }
      return expected("',' or ']'");
    }
  }
  skip();
  if (i != text.size()) return expected("nothing after the array");
  return values.Finish();
}

}  // namespace

std::string Number(double x) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", x);
  return b;
}

std::string ParamsJson(const ParameterView& theta,
                       const std::vector<std::string>& real_names,
                       const SimulatorExperiment* experiment) {
  std::string s = "{\"bits\": [";
  for (std::size_t k = 0; k < theta.bits.size(); ++k) {
    if (k > 0) s += ", ";
    s += theta.bits[k] ? '1' : '0';
  }
  s += "], \"reals\": {";
  for (std::size_t k = 0; k < theta.reals.size(); ++k) {
    if (k > 0) s += ", ";
    s += JsonString(real_names[k]) + ": " + Number(theta.reals[k]);
  }
  s += "}";
  if (experiment != nullptr) {
    s += ", \"experiment\": {\"name\": " + JsonString(experiment->name) +
         ", \"load_x\": " + Number(experiment->load_x) +
         ", \"load_y_fraction\": " + Number(experiment->load_y_fraction) +
         ", \"load_amplitude\": " + Number(experiment->load_force) +
         ", \"frequency\": " + Number(experiment->frequency_hz) + "}";
  }
  return s + "}\n";
}

std::string ParamsCsv(const ParameterView& theta,
                      const std::vector<std::string>& bit_names,
                      const std::vector<std::string>& real_names,
                      const SimulatorExperiment* experiment) {
  std::string s = "name,value\n";
  for (std::size_t k = 0; k < theta.bits.size(); ++k) {
    s += CsvField(bit_names[k]) + ',' + (theta.bits[k] ? '1' : '0') + '\n';
  }
  for (std::size_t k = 0; k < theta.reals.size(); ++k) {
    s += CsvField(real_names[k]) + ',' + Number(theta.reals[k]) + '\n';
  }
  if (experiment != nullptr) {
    s += "experiment," + CsvField(experiment->name) + '\n';
    s += "load_x," + Number(experiment->load_x) + '\n';
    s += "load_y_fraction," + Number(experiment->load_y_fraction) + '\n';
    s += "load_amplitude," + Number(experiment->load_force) + '\n';
    s += "frequency," + Number(experiment->frequency_hz) + '\n';
  }
  return s;
}

std::string RequestLine(std::uint64_t id, const ParameterView& theta) {
  std::string s = std::to_string(id);
  s.reserve(s.size() + theta.bits.size() + 24 * theta.reals.size() + 3);
  s += ' ';
  for (std::uint8_t b : theta.bits) s += b ? '1' : '0';
  if (theta.bits.empty()) s += '-';
  for (double x : theta.reals) s += ' ' + Number(x);
  return s + '\n';
}

std::string ReadValues(std::string_view text, DataFormat format, std::span<double> out) {
  return format == DataFormat::kJson ? ReadJson(text, out) : ReadCsv(text, out);
}

std::string ReadResponse(std::string_view line,
                         std::uint64_t id,
                         std::span<double> out,
                         bool* in_step) {
  *in_step = false;
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  const std::string expected = std::to_string(id);
  const std::string_view whole = line;
  auto unexpected = [&] {
    return "expected an answer \"" + expected + " ok ...\" or \"" + expected +
           " error ...\", got " + Excerpt(whole);
  };
  const std::size_t space = std::min(line.find(' '), line.size());
  const std::string_view answered = line.substr(0, space);
  if (answered != expected) {
    std::uint64_t other = 0;
    const char* last = answered.data() + answered.size();
    const auto [end, ec] = std::from_chars(answered.data(), last, other);
    if (ec == std::errc() && end == last && other != id) {
      return "the worker answered request " + std::to_string(other) + " when request " + expected +
             " was asked (an answer repeated, skipped or out of order)";
    }
    return unexpected();
  }
  line.remove_prefix(std::min(space + 1, line.size()));
  if (line.rfind("error", 0) == 0 && (line.size() == 5 || line[5] == ' ')) {
    *in_step = true;
    return "the worker reported an error: " +
           Printable(line.substr(std::min<std::size_t>(6, line.size())), 200);
  }
  if (line.rfind("ok", 0) != 0 || (line.size() > 2 && line[2] != ' ')) return unexpected();
  *in_step = true;
  Collector values(out);
  std::size_t i = 2;
  while (i < line.size()) {
    if (line[i] == ' ' || line[i] == '\t') {
      ++i;
      continue;
    }
    std::size_t j = i;
    while (j < line.size() && line[j] != ' ' && line[j] != '\t') ++j;
    if (std::string reason = values.Add(line.substr(i, j - i), 0); !reason.empty()) return reason;
    i = j;
  }
  return values.Finish();
}

}  // namespace combabc::simulators_internal
