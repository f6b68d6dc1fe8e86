#include "services/design_campaign.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <regex>
#include <set>
#include <sstream>

#include <toml++/toml.h>

#include "combabc/core/error.hpp"
#include "combabc/data/measured_data.hpp"

namespace combabc::services {
namespace fs = std::filesystem;
namespace {

std::string NextNumber(double x) {
  char b[40];
  std::snprintf(b, sizeof b, "%.6g", x);
  return b;
}

// Millimetres, to a tenth: what a ruler across the strip reads.
std::string NextMm(double metres) {
  char b[40];
  std::snprintf(b, sizeof b, "%.4g", std::round(metres * 1e4) / 10.0);
  return b;
}

// A TOML basic string.
std::string Quote(const std::string& s) {
  std::string out = "\"";
  for (char ch : s) {
    if (ch == '"' || ch == '\\') {
      out += '\\';
      out += ch;
    } else if (static_cast<unsigned char>(ch) < 0x20) {
      char b[8];
      std::snprintf(b, sizeof b, "\\u%04x", static_cast<unsigned>(ch));
      out += b;
    } else {
      out += ch;
    }
  }
  return out + "\"";
}

fs::path AbsoluteNormal(const fs::path& p) { return fs::absolute(p).lexically_normal(); }

// `target` as the next config, in `from`, names it: relative where it can be.
std::string RelativeTo(const fs::path& target, const fs::path& from) {
  const fs::path r = AbsoluteNormal(target).lexically_relative(AbsoluteNormal(from));
  return r.empty() ? AbsoluteNormal(target).generic_string() : r.generic_string();
}

// The name of an experiment at this load and scan line: "x20cm_y8mm_scan20mm".
std::string ExperimentName(double load_x, double load_y, double scan_y, double width) {
  return "x" + NextNumber(load_x * 100) + "cm_y" + NextMm(load_y * width) + "mm_scan" +
         NextMm(scan_y * width) + "mm";
}

// The config's text as lines, edited in place: string literals replaced at toml++'s source
// positions, whole lines renamed, lines inserted.
class TextEdits {
 public:
  TextEdits(const std::string& text, std::string path) : path_(std::move(path)) {
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) lines_.push_back(line);
  }

  // The string literal that `node` (a string value) starts, replaced by `value` when Apply runs.
  void ReplaceString(const toml::node& node, const std::string& value, const std::string& key) {
    const toml::source_position at = node.source().begin;
    const auto line = static_cast<std::size_t>(at.line) - 1;
    const auto column = static_cast<std::size_t>(at.column) - 1;
    if (line >= lines_.size() || column >= lines_[line].size()) {
      Refuse(static_cast<int>(at.line), key, "cannot find its value in the text");
    }
    const std::string& text = lines_[line];
    const char quote = text[column];
    std::size_t end = std::string::npos;
    if ((quote == '"' || quote == '\'') && text.compare(column, 3, std::string(3, quote)) != 0) {
      for (std::size_t i = column + 1; i < text.size(); ++i) {
        if (quote == '"' && text[i] == '\\') {
          ++i;
        } else if (text[i] == quote) {
          end = i;
          break;
        }
      }
    }
    if (end == std::string::npos) {
      Refuse(
          static_cast<int>(at.line), key, "write it as a one-line string to let design rebase it");
    }
    strings_.push_back({line, column, end + 1 - column, Quote(value)});
  }

  void Insert(std::size_t before_line, std::vector<std::string> lines) {
    inserts_.push_back({before_line, std::move(lines)});
  }

  std::vector<std::string>& lines() { return lines_; }

  std::string Apply() {
    std::sort(strings_.begin(), strings_.end(), [](const Replace& a, const Replace& b) {
      return a.line != b.line ? a.line > b.line : a.column > b.column;
    });
    for (const Replace& r : strings_) lines_[r.line].replace(r.column, r.length, r.text);
    std::stable_sort(inserts_.begin(), inserts_.end(), [](const Lines& a, const Lines& b) {
      return a.before > b.before;
    });
    for (const Lines& l : inserts_) {
      lines_.insert(
          lines_.begin() + static_cast<std::ptrdiff_t>(l.before), l.lines.begin(), l.lines.end());
    }
    std::string out;
    for (const std::string& line : lines_) out += line + "\n";
    return out;
  }

  [[noreturn]] void Refuse(int line, const std::string& key, const std::string& why) const {
    throw Error(ErrorKind::kUsage, "design cannot write the next config: " + why, path_, line, key);
  }

 private:
  struct Replace {
    std::size_t line, column, length;
    std::string text;
  };
  struct Lines {
    std::size_t before;
    std::vector<std::string> lines;
  };
  std::string path_;
  std::vector<std::string> lines_;
  std::vector<Replace> strings_;
  std::vector<Lines> inserts_;
};

// The schedule keys of a component, as the config reader takes them.
void ScheduleKeys(const ThresholdSchedule& s, std::ostream& out) {
  switch (s.kind) {
    case ThresholdKind::kList: {
      out << "threshold = [";
      for (std::size_t i = 0; i < s.values.size(); ++i) {
        out << (i ? ", " : "") << NextNumber(s.values[i]);
      }
      out << "]\n";
      return;
    }
    case ThresholdKind::kQuantile:
      out << "quantile = " << NextNumber(s.quantile) << "\n";
      if (s.weighted) out << "weighted = true\n";
      break;
    case ThresholdKind::kAcceptance:
      out << "acceptance_rate = " << NextNumber(s.acceptance_rate) << "\n";
      break;
    case ThresholdKind::kEss:
      out << "ess_fraction = " << NextNumber(s.ess_fraction) << "\n";
      break;
  }
  if (std::isfinite(s.initial)) out << "initial = " << NextNumber(s.initial) << "\n";
  out << "target = " << NextNumber(s.target) << "\n";
}

// The component whose noise treatment and schedule the new experiment takes: the first
// noise-aware least_squares one of the experiments so far (gaussian or folded normal), else the
// first least_squares one, else the first threshold one (the new one is a least_squares over its
// scan).
const MetricComponentConfig* Reference(const CalibrationConfig& c) {
  const MetricComponentConfig* first_ls = nullptr;
  const MetricComponentConfig* first = nullptr;
  for (const ExperimentConfig& x : c.experiments) {
    for (const MetricComponentConfig& m : x.metric.components) {
      if (m.type == MetricType::kLeastSquares && m.noise.model != NoiseModel::kNone) return &m;
      if (m.type == MetricType::kLeastSquares && !first_ls) first_ls = &m;
      if (KindOf(m.type) == ComponentKind::kThreshold && !first) first = &m;
    }
  }
  return first_ls ? first_ls : first;
}

std::string ExperimentBlock(const CalibrationConfig& c,
                            const DesignCandidate& k,
                            const std::string& name,
                            const std::string& csv,
                            std::size_t number) {
  const DataConfig& data = c.experiments.back().data;
  const double unit = MetresPer(data.position_unit);
  const double width = c.model.width;
  const std::string window =
      "[" + NextNumber(k.scan_from / unit) + ", " + NextNumber(k.scan_to / unit) + "]";
  const char* position_unit = ToString(data.position_unit);
  std::ostringstream out;
  out << "\n# Experiment " << number << ", chosen by `combabc design`: the shaker at "
      << NextNumber(k.load_x * 100) << " cm along the strip, " << NextMm(k.load_y_fraction * width)
      << " mm from edge 1; the scan " << NextNumber(k.scan_from * 100) << "-"
      << NextNumber(k.scan_to * 100) << " cm every " << NextNumber(c.design->scan_spacing * 100)
      << " cm on the line " << NextMm(k.scan_y_fraction * width) << " mm from edge 1.\n"
      << "[[experiment]]\nname = " << Quote(name) << "\n"
      << "[experiment.load]\nx = " << NextNumber(k.load_x) << "  # m\n"
      << "y_fraction = " << NextNumber(k.load_y_fraction) << "  # "
      << NextMm(k.load_y_fraction * width) << " mm from edge 1 (y = 0) of the " << NextMm(width)
      << " mm width\n"
      << "[experiment.output]\npositions = [";
  const std::vector<double> x = DesignScanPositions(k.scan_from, k.scan_to, c.design->scan_spacing);
  for (std::size_t i = 0; i < x.size(); ++i) {
    out << (i == 0 ? "" : i % 10 == 0 ? ",\n  " : ", ") << NextNumber(x[i]);
  }
  out << "]  # m\ny_fraction = " << NextNumber(k.scan_y_fraction) << "  # the scan line, "
      << NextMm(k.scan_y_fraction * width) << " mm from edge 1\n"
      << "[experiment.data]\ncsv = " << Quote(csv) << "\n"
      << "position_column = " << Quote(data.position_column) << "\n"
      << "displacement_column = " << Quote(data.displacement_column) << "\n"
      << "position_unit = " << Quote(position_unit) << "\n"
      << "displacement_unit = " << Quote(ToString(data.displacement_unit)) << "\n";
  if (!data.normalise) out << "normalise = false\n";
  out << "window = " << window << "  # " << position_unit << "\n"
      << "[experiment.metric]\n[[experiment.metric.component]]\ntype = \"least_squares\"\n"
      << "window = " << window << "  # " << position_unit << "\n";
  const MetricComponentConfig* ref = Reference(c);
  if (ref != nullptr && ref->type == MetricType::kLeastSquares &&
      ref->noise.model != NoiseModel::kNone) {
    // An amplitude scan's noise folds at zero as the others' does (docs/algorithm.md).
    out << "noise = "
        << (ref->noise.model == NoiseModel::kFoldedNormal ? "\"folded_normal\"" : "\"gaussian\"")
        << "\n";
    if (ref->noise.sigma_noise) {
      out << "sigma_noise = " << NextNumber(*ref->noise.sigma_noise)
          << "  # as the experiments before\n";
    } else {
      out << "sigma_noise = \"estimate\"  # from this experiment's data, as the others\n";
    }
    if (ref->noise.sigma_model > 0.0) {
      out << "sigma_model = " << NextNumber(ref->noise.sigma_model) << "\n";
    }
  }
  if (ref != nullptr) ScheduleKeys(ref->threshold, out);
  return out.str();
}

// The shorthand's [data] / [metric] headers (and their sub-tables) as experiment 1's.
const std::regex kShorthandHeader(
    R"(^(\s*)\[(\[?)\s*(data|metric)((\s*\.[^\]]*)?)\s*\](\]?)(.*)$)");

}  // namespace

std::string ClampWhere(const CalibrationConfig& c, int bit) {
  const int n = c.model.clamps_per_edge;
  const double section = c.model.length / n;
  const int s = bit % n;
  return "clamp " + std::to_string(bit + 1) + " (edge " + std::to_string(bit < n ? 1 : 2) + ", " +
         NextNumber(s * section * 100) + "-" + NextNumber((s + 1) * section * 100) + " cm)";
}

NextStep WriteNextConfig(const CalibrationConfig& c,
                         const DesignCandidate& k,
                         const fs::path& design_directory) {
  toml::table root;
  try {
    root = toml::parse(c.text, c.path);
  } catch (const toml::parse_error& e) {
    throw Error(
        ErrorKind::kSoftware, std::string("cannot re-read the config: ") + e.what(), c.path);
  }
  TextEdits edits(c.text, c.path);
  const fs::path config_directory = c.directory.empty() ? fs::path(".") : fs::path(c.directory);
  auto rebase = [&](const toml::node* node, const std::string& original, const std::string& key) {
    if (node == nullptr || fs::path(original).is_absolute()) return;
    edits.ReplaceString(*node, RelativeTo(config_directory / original, design_directory), key);
  };
  const bool shorthand = !root.contains("experiment");
  std::set<std::string> names;
  if (shorthand) {
    rebase(root.at_path("data.csv").node(), c.experiments.front().data.csv, "data.csv");
    // Experiment 1 keeps [model.load] and [model.output], which [[experiment]] tables default to.
    const ExperimentConfig& x = c.experiments.front();
    const std::string name = ExperimentName(
        x.load.load_x, x.load.load_y_fraction, x.load.output_y_fraction, c.model.width);
    names.insert(ColumnKey(name));
    std::vector<std::string>& lines = edits.lines();
    std::size_t first = lines.size();
    for (std::size_t i = 0; i < lines.size(); ++i) {
      if (!std::regex_match(lines[i], kShorthandHeader)) continue;
      first = std::min(first, i);
      lines[i] = std::regex_replace(lines[i], kShorthandHeader, "$1[$2experiment.$3$4]$6$7");
    }
    if (first == lines.size()) {
      edits.Refuse(1, "data", "its [data] and [metric] are not written as tables");
    }
    edits.Insert(first,
                 {"# Experiment 1: the single-experiment [data] and [metric], converted by "
                  "`combabc design`.",
                  "[[experiment]]",
                  "name = " + Quote(name)});
  } else {
    const toml::array* experiments = root["experiment"].as_array();
    for (std::size_t e = 0; experiments && e < experiments->size(); ++e) {
      const std::string key = "experiment[" + std::to_string(e) + "].data.csv";
      rebase(root.at_path("experiment[" + std::to_string(e) + "].data.csv").node(),
             c.experiments.at(e).data.csv,
             key);
      names.insert(ColumnKey(c.experiments.at(e).name));
    }
  }
  // The new experiment: its name unique among the others, its data beside the run's output
  // directory, where the campaign keeps its files.
  std::string name = ExperimentName(k.load_x, k.load_y_fraction, k.scan_y_fraction, c.model.width);
  for (int n = 2; names.count(ColumnKey(name)) != 0; ++n) {
    name = ExperimentName(k.load_x, k.load_y_fraction, k.scan_y_fraction, c.model.width) + "_" +
           std::to_string(n);
  }
  NextStep next;
  next.experiment_name = name;
  const fs::path output = AbsoluteNormal(config_directory / c.output.directory);
  next.data_path = (output.parent_path() / (name + ".csv")).string();
  const std::size_t count = c.experiments.size() + 1;
  const std::string stem =
      std::regex_replace(output.filename().string(), std::regex(R"(-e[0-9]+$)"), "");
  next.output_directory = (output.parent_path() / (stem + "-e" + std::to_string(count))).string();
  const std::string directory = RelativeTo(next.output_directory, design_directory);
  std::string tail;
  if (const toml::node* node = root.at_path("output.directory").node()) {
    edits.ReplaceString(*node, directory, "output.directory");
  } else if (const toml::table* table = root["output"].as_table()) {
    const auto line = static_cast<std::size_t>(table->source().begin.line);
    if (table->is_inline() || line == 0) {
      edits.Refuse(static_cast<int>(line), "output", "write [output] as a table");
    }
    edits.Insert(line, {"directory = " + Quote(directory) + "  # the next run's, by design"});
  } else {
    tail = "\n[output]\ndirectory = " + Quote(directory) + "  # the next run's, by design\n";
  }
  next.config_text =
      edits.Apply() + tail +
      ExperimentBlock(c, k, name, RelativeTo(next.data_path, design_directory), count);
  // What the next run will read: refused here, not on the bench, if the conversion went wrong.
  try {
    const CalibrationConfig check =
        ParseConfig(next.config_text, (design_directory / "next.toml").string());
    if (check.experiments.size() != count) {
      throw Error(
          ErrorKind::kSoftware,
          std::to_string(check.experiments.size()) + " experiments, not " + std::to_string(count));
    }
  } catch (const Error& e) {
    throw Error(ErrorKind::kSoftware,
                "the next config design wrote does not read back (" + e.message() + " at line " +
                    std::to_string(e.line()) + ", " + e.field() +
                    "); please report it with the config",
                c.path);
  }
  return next;
}

std::vector<std::string> Instructions(const CalibrationConfig& c,
                                      const DesignCandidate& k,
                                      const NextStep& next,
                                      const std::string& next_config_path) {
  const double width = c.model.width;
  const DataConfig& data = c.experiments.back().data;
  const std::size_t points =
      DesignScanPositions(k.scan_from, k.scan_to, c.design->scan_spacing).size();
  const int n = c.model.clamps_per_edge;
  std::vector<std::string> out;
  out.push_back("1. Put the shaker at " + NextNumber(k.load_x * 100) + " cm along the strip, " +
                NextMm(k.load_y_fraction * width) + " mm from edge 1 (edge 1 holds clamps 1-" +
                std::to_string(n) + "; the strip is " + NextMm(width) + " mm wide).");
  out.push_back("2. Scan the line " + NextMm(k.scan_y_fraction * width) + " mm from edge 1, from " +
                NextNumber(k.scan_from * 100) + " to " + NextNumber(k.scan_to * 100) +
                " cm, every " + NextNumber(c.design->scan_spacing * 100) + " cm (" +
                std::to_string(points) + " points).");
  // Paths as seen from here, where the user runs the commands.
  auto here = [](const std::string& path) {
    std::error_code ec;
    const fs::path cwd = fs::current_path(ec);
    return ec ? path : fs::path(path).lexically_proximate(cwd).generic_string();
  };
  out.push_back("3. Save the profile as " + here(next.data_path) + ": columns " +
                data.position_column + " (" + ToString(data.position_unit) + ") and " +
                data.displacement_column + " (" + ToString(data.displacement_unit) +
                "), one row per point.");
  out.push_back("4. Calibrate with every experiment: combabc run " + next_config_path);
  out.push_back("5. Then design the next one: combabc design " + next_config_path +
                " --posterior " +
                here((fs::path(next.output_directory) / c.output.database).string()));
  return out;
}

}  // namespace combabc::services
