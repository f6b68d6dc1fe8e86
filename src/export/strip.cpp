#include "combabc/export/strip.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "export/json_text.hpp"

namespace combabc {
namespace {

using export_text::JsonNumber;
using export_text::JsonString;

// The label column left of the strip ("edge 2 "): the strip gets the rest of the line.
constexpr int kStripLabel = 7;
// Rows of the strip's inside, between its edges: enough to tell a load or scan line near either
// edge from one on the centreline.
constexpr int kStripInside = 3;

// Centimetres to 0.1 cm without trailing zeros ("45", "47.5"); names differ from answer.cpp's
// helpers because unity builds share one translation unit.
std::string StripCm(double metres) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f", metres * 100.0);
  std::string s = text;
  if (s.size() > 2 && s.compare(s.size() - 2, 2, ".0") == 0) s.resize(s.size() - 2);
  return s == "-0" ? "0" : s;
}

std::string StripMm(double metres) {
  char text[32];
  std::snprintf(text, sizeof text, "%.0f", metres * 1000.0);
  return std::string(text) == "-0" ? "0" : text;
}

// The symbol of a section: its verdict, or its P(fixed) in tenths when not determined.
char SectionSymbol(const AnswerBit& bit) {
  if (bit.verdict == Verdict::kFixed) return '#';
  if (bit.verdict == Verdict::kFree) return '.';
  return static_cast<char>('0' + std::clamp(static_cast<int>(bit.p_one * 10.0), 0, 9));
}

// The ANSI colours of a section: the report's scale, linear from rgb(242, 242, 242) at P = 0 to
// rgb(27, 120, 55) at P = 1 (docs/history.md, "The strip"), each channel at the nearest level of
// the xterm 256-colour cube; black text, white on the darker half.
std::string SectionColour(double p, bool colour256) {
  p = std::clamp(p, 0.0, 1.0);
  if (!colour256) {
    // The basic 8: white (free side), yellow (not determined), green (fixed side).
    if (p >= kVerdictLevel) return "\033[42;30m";
    if (p <= 1.0 - kVerdictLevel) return "\033[47;30m";
    return "\033[43;30m";
  }
  const auto level = [p](double at0, double at1) {
    static constexpr double kLevels[] = {0, 95, 135, 175, 215, 255};  // xterm's cube
    const double value = at0 + (at1 - at0) * p;
    int nearest = 0;
    for (int k = 1; k < 6; ++k) {
      if (std::abs(kLevels[k] - value) < std::abs(kLevels[nearest] - value)) nearest = k;
    }
    return nearest;
  };
  const int cube = 16 + 36 * level(242, 27) + 6 * level(242, 120) + level(242, 55);
  return "\033[48;5;" + std::to_string(cube) + "m\033[38;5;" + (p > 0.6 ? "15" : "16") + "m";
}

char ExperimentMark(std::size_t k) {
  if (k < 9) return static_cast<char>('1' + k);
  if (k < 35) return static_cast<char>('a' + (k - 9));
  return '*';
}

// A group of the verdict line: its numbers (or names), or their count when there are many.
std::string VerdictGroup(const std::string& title,
                         const std::vector<std::string>& members,
                         const char* what) {
  std::string out = title + ": ";
  if (members.empty()) return out + "none";
  if (members.size() > kVerdictLineList) {
    return out + std::to_string(members.size()) + " " + what;
  }
  for (std::size_t k = 0; k < members.size(); ++k) out += (k ? ", " : "") + members[k];
  return out;
}

// Writes `text` into `line` from column `at`, if it fits and does not reach `next_free`;
// returns the next free column.
int Place(std::string& line, int at, const std::string& text, int next_free) {
  const int end = at + static_cast<int>(text.size());
  if (at < next_free || at < 0 || end > static_cast<int>(line.size())) return next_free;
  line.replace(static_cast<std::size_t>(at), text.size(), text);
  return end + 1;
}

// The centimetre axis under the strip: ticks at a round step at least 6 columns apart, the
// length at the right end.
std::string AxisLine(double length_m, int cells, int columns) {
  std::string line(static_cast<std::size_t>(columns), ' ');
  line.replace(0, 6, "x (cm)");
  const double length_cm = length_m * 100.0;
  const auto column = [&](double cm) {
    return kStripLabel + static_cast<int>(std::lround(cm / length_cm * cells));
  };
  double step = 0.0;
  for (double decade = 1e-3; step == 0.0; decade *= 10.0) {
    for (double m : {1.0, 2.0, 5.0}) {
      if (step == 0.0 && m * decade / length_cm * cells >= 6.0) step = m * decade;
    }
  }
  const std::string end = StripCm(length_m);
  // The right end first: a tick that would touch it is left out.
  const int end_at = std::min(column(length_cm), columns - static_cast<int>(end.size()));
  Place(line, end_at, end, 0);
  int next_free = kStripLabel;
  for (int k = 0; k * step < length_cm - 1e-9; ++k) {
    const std::string text = StripCm(k * step / 100.0);
    const int at = column(k * step) - (k == 0 ? 0 : static_cast<int>(text.size()) / 2);
    if (at + static_cast<int>(text.size()) < end_at) next_free = Place(line, at, text, next_free);
  }
  while (!line.empty() && line.back() == ' ') line.pop_back();
  return line;
}

}  // namespace

std::string StripJson(const StripLayout& s, int indent) {
  const std::string pad(static_cast<std::size_t>(indent), ' ');
  std::string out =
      "{\"length_m\": " + JsonNumber(s.length_m) + ", \"width_m\": " + JsonNumber(s.width_m) +
      ", \"clamps_per_edge\": " + std::to_string(s.clamps_per_edge) + ", \"experiments\": [";
  for (std::size_t k = 0; k < s.experiments.size(); ++k) {
    const StripExperiment& x = s.experiments[k];
    out += (k ? "," : "") + std::string("\n") + pad + "  {\"name\": " + JsonString(x.name) +
           ", \"load_x_m\": " + JsonNumber(x.load_x_m) +
           ", \"load_y_m\": " + JsonNumber(x.load_y_m) +
           ", \"scan_from_m\": " + JsonNumber(x.scan_from_m) +
           ", \"scan_to_m\": " + JsonNumber(x.scan_to_m) +
           ", \"scan_y_m\": " + JsonNumber(x.scan_y_m) + "}";
  }
  out += s.experiments.empty() ? "]}" : "\n" + pad + "]}";
  return out;
}

std::string VerdictLine(const Answer& a, bool sensor) {
  std::vector<std::string> fixed_bits;
  std::vector<std::string> free_bits;
  std::vector<std::string> open_bits;
  for (const AnswerBit& bit : a.bits) {
    const std::string label = sensor ? std::to_string(bit.number) : bit.name;
    if (bit.verdict == Verdict::kFixed) {
      fixed_bits.push_back(label);
    } else if (bit.verdict == Verdict::kFree) {
      free_bits.push_back(label);
    } else {
      open_bits.push_back(label);
    }
  }
  const char* what = sensor ? "clamps" : "bits";
  return VerdictGroup(sensor ? "fixed" : "bit = 1", fixed_bits, what) + "; " +
         VerdictGroup(sensor ? "free" : "bit = 0", free_bits, what) + "; " +
         VerdictGroup("not determined", open_bits, what);
}

TextStyle TerminalStyle(int fd) {
  TextStyle style;
  const char* term = std::getenv("TERM");
  const char* no_colour = std::getenv("NO_COLOR");
  const bool refused = no_colour != nullptr && *no_colour != '\0';
  style.colour = !refused && ::isatty(fd) != 0 && term != nullptr && *term != '\0' &&
                 std::strcmp(term, "dumb") != 0;
  const char* colour_term = std::getenv("COLORTERM");
  style.colour256 = style.colour && (std::strstr(term, "256") != nullptr ||
                                     (colour_term != nullptr && *colour_term != '\0'));
  return style;
}

std::string StripText(const Answer& a, const StripLayout& strip, const TextStyle& style) {
  const int n = strip.clamps_per_edge;
  if (n <= 0 || a.bits.size() != 2 * static_cast<std::size_t>(n) || !(strip.length_m > 0.0)) {
    return "";
  }
  const std::string verdicts = "verdict: " + VerdictLine(a, true) + "\n";
  // Each section is `cell` columns: its symbol, then a "|" between sections.
  const int cell = (style.columns - kStripLabel - 1) / n;
  if (cell < 1) {
    return "the strip: " + std::to_string(n) + " sections per edge do not fit in " +
           std::to_string(style.columns) + " columns (the report draws it)\n" + verdicts;
  }
  const int cells = n * cell;
  const int columns = kStripLabel + 1 + cells;
  const auto blank = [&] { return std::string(static_cast<std::size_t>(columns), ' '); };
  const auto inside_column = [&](double x_m) {
    const auto at = static_cast<int>(std::floor(x_m / strip.length_m * cells));
    return kStripLabel + 1 + std::clamp(at, 0, cells - 1);
  };
  std::string out = "the strip to scale along its length, " + StripCm(strip.length_m) +
                    " cm: " + std::to_string(n) + " clamp sections per edge of " +
                    StripCm(strip.length_m / n) + " cm\n";

  const auto numbers = [&](int first) {
    std::string line = blank();
    int next_free = 0;
    for (int s = 0; s < n; ++s) {
      const std::string text = std::to_string(first + s);
      const int content = std::max(cell - 1, 1);
      const int at =
          kStripLabel + 1 + s * cell + std::max(0, content - static_cast<int>(text.size()));
      next_free = Place(line, at, text, next_free);
    }
    while (!line.empty() && line.back() == ' ') line.pop_back();
    return line + "\n";
  };
  const auto edge = [&](int number) {
    std::string line = "edge " + std::to_string(number) + " |";
    line.resize(kStripLabel + 1, ' ');
    line[kStripLabel] = '|';
    for (int s = 0; s < n; ++s) {
      const AnswerBit& bit =
          a.bits[static_cast<std::size_t>(number - 1) * static_cast<std::size_t>(n) +
                 static_cast<std::size_t>(s)];
      const int content = cell > 1 ? cell - 1 : 1;
      std::string text(static_cast<std::size_t>(content), ' ');
      const char symbol = SectionSymbol(bit);
      if (bit.verdict == Verdict::kNotDetermined) {
        text[static_cast<std::size_t>(content / 2)] = symbol;
      } else {
        text.assign(static_cast<std::size_t>(content), symbol);
      }
      line += style.colour ? SectionColour(bit.p_one, style.colour256) + text + "\033[0m" : text;
      if (cell > 1) line += '|';
    }
    if (cell == 1) line += '|';
    return line + "\n";
  };

  // The inside: each experiment's scan line, then the loads over them, in the row of their y.
  std::vector<std::string> inside(kStripInside, blank());
  const auto row_of = [&](double y_m) {
    const double fraction = strip.width_m > 0.0 ? y_m / strip.width_m : 0.5;
    const auto from_top = static_cast<int>(std::floor((1.0 - fraction) * kStripInside));
    return static_cast<std::size_t>(std::clamp(from_top, 0, kStripInside - 1));
  };
  for (const StripExperiment& x : strip.experiments) {
    std::string& row = inside[row_of(x.scan_y_m)];
    for (int c = inside_column(x.scan_from_m); c <= inside_column(x.scan_to_m); ++c) {
      row[static_cast<std::size_t>(c)] = '-';
    }
  }
  for (std::size_t k = 0; k < strip.experiments.size(); ++k) {
    const StripExperiment& x = strip.experiments[k];
    inside[row_of(x.load_y_m)][static_cast<std::size_t>(inside_column(x.load_x_m))] =
        ExperimentMark(k);
  }

  out += numbers(n + 1) + edge(2);
  for (std::string& row : inside) {
    row[kStripLabel] = '|';
    row[static_cast<std::size_t>(columns - 1)] = '|';
    out += row + "\n";
  }
  out += edge(1) + numbers(1) + AxisLine(strip.length_m, cells, columns) + "\n";
  out += " # fixed  . free  0-9 not determined: P(fixed) in tenths  - scan line  1 load\n";
  for (std::size_t k = 0; k < strip.experiments.size(); ++k) {
    const StripExperiment& x = strip.experiments[k];
    // A long name would push the line past the terminal's width.
    const std::string name = x.name.size() > 16 ? x.name.substr(0, 15) + "~" : x.name;
    out += std::string(" ") + ExperimentMark(k) + (name.empty() ? "" : " " + name) + ": load at " +
           StripCm(x.load_x_m) + " cm, " + StripMm(x.load_y_m) + " mm from edge 1; scan " +
           StripCm(x.scan_from_m) + "-" + StripCm(x.scan_to_m) + " cm at " + StripMm(x.scan_y_m) +
           " mm\n";
  }
  return out + verdicts;
}

}  // namespace combabc
