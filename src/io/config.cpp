#include "combabc/io/config.hpp"

#include <cctype>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>

#include "bounded_read.hpp"
#include "combabc/core/error.hpp"
#include "config_reader.hpp"

namespace combabc {
namespace {

using config_internal::OneOf;
using config_internal::Source;
using config_internal::Sources;
using config_internal::TableReader;
using config_internal::WindowKey;

LengthUnit UnitKey(TableReader& t, std::string_view key, LengthUnit fallback) {
  return t.Choice<LengthUnit>(key, ParseLengthUnit, "unit", {"m", "cm", "mm", "um", "nm"})
      .value_or(fallback);
}

// ---------------------------------------------------------------------------------------- data
void ParseData(TableReader& root, CalibrationConfig* c) {
  auto t = root.Table("data");
  if (!t) throw Error(ErrorKind::kConfig, "missing required table [data]", c->path, 1, "data");
  DataConfig& d = c->data;
  const auto csv = t->String("csv");
  if (!csv || csv->empty()) t->Fail("csv", "missing required key (path of the measured CSV)");
  d.csv = *csv;
  d.position_column = t->String("position_column").value_or(d.position_column);
  d.displacement_column = t->String("displacement_column").value_or(d.displacement_column);
  if (d.position_column == d.displacement_column) {
    t->Fail("displacement_column", "must differ from position_column");
  }
  d.position_unit = UnitKey(*t, "position_unit", d.position_unit);
  d.displacement_unit = UnitKey(*t, "displacement_unit", d.displacement_unit);
  const double unit = MetresPer(d.position_unit);
  if (t->Has("window")) {
    const auto [lo, hi] = WindowKey(*t, "window", unit);
    d.window_min = lo;
    d.window_max = hi;
  }
  d.normalise = t->Bool("normalise").value_or(d.normalise);

  if (auto g = t->Table("gaussian_extension")) {
    GaussianExtensionOptions& e = d.gaussian_extension;
    e.enabled = g->Bool("enabled").value_or(true);  // the table's presence asks for it
    // Default: the model's load position (the paper fits "centred at the shaker location").
    e.impact_position = c->model.load_x;
    if (const auto impact = g->Number("impact_position")) {
      if (!std::isfinite(*impact)) g->Fail("impact_position", "must be finite");
      e.impact_position = *impact * unit;
    }
    e.fit_offset = g->Bool("fit_offset").value_or(e.fit_offset);
    e.fit_points = g->IntegerIn("fit_points", e.fit_points, e.fit_offset ? 3 : 2, 100000);
    if (const auto spacing = g->Number("spacing")) {
      if (!(*spacing > 0.0) || !std::isfinite(*spacing)) {
        g->Fail("spacing", "must be > 0 (in position_unit)");
      }
      e.spacing = *spacing * unit;
    }
    g->Finish();
  }
  t->Finish();
}

// --------------------------------------------------------------------------------------- output
void ParseOutput(TableReader& root, CalibrationConfig* c) {
  auto t = root.Table("output");
  if (!t) return;
  OutputConfig& o = c->output;
  o.directory = t->String("directory").value_or(o.directory);
  if (o.directory.empty()) t->Fail("directory", "must not be empty");
  o.database = t->String("database").value_or(o.database);
  if (o.database.empty() || o.database.find('/') != std::string::npos) {
    t->Fail("database", "must be a file name (it is created inside output.directory)");
  }
  if (const auto formats = t->Strings("figures")) {
    for (const std::string& f : *formats) {
      if (f != "png" && f != "svg" && f != "pdf") {
        t->Fail(
            "figures",
            "unknown figure format " + Excerpt(f) + "; expected " + OneOf({"png", "svg", "pdf"}));
      }
    }
    o.figure_formats = *formats;
  }
  o.keep_simulated_curves = t->Bool("keep_simulated_curves").value_or(o.keep_simulated_curves);
  t->Finish();
}

// A failed IsValid() message starts "SmcOptions::field..." or "BinarySpaceOptions::field...":
// report it at the config key that set that field.
[[noreturn]] void ThrowAttributed(const std::string& why,
                                  const std::string& prefix,
                                  const std::map<std::string, Source>& map,
                                  const Source& fallback,
                                  const std::string& path) {
  std::string field;
  if (why.rfind(prefix, 0) == 0) {
    std::size_t end = prefix.size();
    while (end < why.size() && (std::isalnum(static_cast<unsigned char>(why[end])) ||
                                why[end] == '_' || why[end] == '[' || why[end] == ']')) {
      ++end;
    }
    field = why.substr(prefix.size(), end - prefix.size());
  }
  auto it = map.find(field);
  if (it == map.end()) it = map.find(field.substr(0, field.find('[')));
  const Source& source = it != map.end() ? it->second : fallback;
  throw Error(ErrorKind::kConfig, why, path, source.line, source.key);
}

}  // namespace

CalibrationConfig ParseConfig(std::string_view text, const std::string& path) {
  CalibrationConfig c;
  c.path = path;
  c.directory = std::filesystem::path(path).parent_path().string();
  c.text = std::string(text);

  toml::table table;
  try {
    table = toml::parse(text, path);
  } catch (const toml::parse_error& e) {
    throw Error(ErrorKind::kConfig,
                "malformed TOML: " + std::string(e.description()),
                path,
                static_cast<int>(e.source().begin.line));
  }
  TableReader root(table, "", c.path);
  Sources sources;
  sources.sampler = {"sampler", 1};
  c.description = root.String("description").value_or("");
  const int dimension = config_internal::ParseModelSection(root, &c);
  ParseData(root, &c);
  config_internal::ParseSamplerSection(root, dimension, &c, &sources);
  config_internal::ParseMetricSection(root, &c);
  ParseOutput(root, &c);
  root.Finish();

  // One schedule per threshold component, in order (SmcOptions::thresholds' contract).
  c.smc.thresholds.clear();
  for (const MetricComponentConfig& component : c.metric.components) {
    if (KindOf(component.type) == ComponentKind::kThreshold) {
      c.smc.thresholds.push_back(component.threshold);
    }
  }
  c.smc.keep_outputs = c.output.keep_simulated_curves;
  c.model.normalise = c.data.normalise;

  std::string why;
  if (!c.smc.IsValid(&why)) {
    ThrowAttributed(why, "SmcOptions::", sources.smc, sources.sampler, c.path);
  }
  if (!c.space.IsValid(&why)) {
    ThrowAttributed(why, "BinarySpaceOptions::", sources.space, sources.sampler, c.path);
  }
  return c;
}

CalibrationConfig LoadConfig(const std::string& path) {
  const std::string text =
      io_internal::ReadBoundedFile(path, kMaxConfigBytes, "config file", ErrorKind::kConfig);
  return ParseConfig(text, path);
}

}  // namespace combabc
