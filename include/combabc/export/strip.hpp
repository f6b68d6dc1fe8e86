#pragma once
// The picture of the sensor strip (docs/history.md, "The strip"): the plate to scale with its two
// rows of clamp sections, each marked by its P(fixed) and verdict, and the load and scan line of
// every experiment. summary.json's "strip" (StripJson) carries the layout for the report's page,
// which draws it at the top of index.html; StripText draws it for a terminal at the end of
// `combabc run` / `resume` / `enumerate`, with the one-line verdict (VerdictLine). Simulators other
// than the sensor have no strip.
#include <string>
#include <vector>

#include "combabc/export/answer.hpp"

namespace combabc {

// One experiment's load and scan line on the strip, in metres; y from edge 1 (y = 0).
struct StripExperiment {
  std::string name;  // "" for a config's single experiment
  double load_x_m = 0.0;
  double load_y_m = 0.0;
  double scan_from_m = 0.0;  // the scan line's first and last output positions
  double scan_to_m = 0.0;
  double scan_y_m = 0.0;
};

// The strip's geometry, from the run's [model]: clamp k (from 1) is section k of edge 1 for
// k <= clamps_per_edge, else section k - clamps_per_edge of edge 2 (BitPosition).
struct StripLayout {
  double length_m = 0.0;
  double width_m = 0.0;
  int clamps_per_edge = 0;
  std::vector<StripExperiment> experiments;
};

// summary.json's "strip" object (docs/history.md), indented by `indent` spaces after its first
// line.
std::string StripJson(const StripLayout& strip, int indent = 2);

// The verdicts in one line: "fixed: 12, 30; free: 10, 11, 28, 29; not determined: 30 clamps".
// Each group lists its numbers up to kVerdictLineList of them, else counts them; the sensor's
// bits are clamps (numbers), other simulators' bits are named ("bit = 1: a, b; ...").
inline constexpr std::size_t kVerdictLineList = 12;
std::string VerdictLine(const Answer& answer, bool sensor);

// How a terminal shows the strip: its width in columns, and whether it takes ANSI colours
// (256 of them, or the basic 8).
struct TextStyle {
  int columns = 80;
  bool colour = false;
  bool colour256 = false;
};

// The style of the terminal on file descriptor `fd`: colour only on a terminal (isatty) whose TERM
// is set and not "dumb", and never when NO_COLOR is set and not empty (no-color.org); 256 colours
// when TERM says so (…256color) or COLORTERM is set. Always 80 columns: the strip is drawn once,
// at the end, and 80 fit every terminal and log.
TextStyle TerminalStyle(int fd);

// The strip for a terminal, `style.columns` wide: edge 2 on top, edge 1 below, between them the
// strip's inside with each experiment's scan line (-) and load (its number); clamp numbers
// outside each edge and a centimetre axis under it. A section shows "#" fixed, "." free, or its
// P(fixed) in tenths (0-9) when not determined; with colour its background follows P(fixed)
// too. Then the legend and VerdictLine. Empty when the answer has no bits or their count is not
// two edges of strip.clamps_per_edge; a note instead of the picture when the sections do not fit.
std::string StripText(const Answer& answer, const StripLayout& strip, const TextStyle& style = {});

}  // namespace combabc
