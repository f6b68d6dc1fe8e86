// [[experiment]] tables, or the single experiment of the shorthand keys ([model.load],
// [model.output], [data], [metric]): each experiment's load and scan, measured data and metric.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <string>

#include "combabc/config/config.hpp"
#include "combabc/core/error.hpp"
#include "config_reader.hpp"

namespace combabc {

std::string ExperimentConfig::Key(std::size_t index, const std::string& table) const {
  if (line == 0) return table;
  return "experiment[" + std::to_string(index) + "]" + (table.empty() ? "" : "." + table);
}

namespace {

// One plan per distinct frequency; each load case scans the experiment's output coordinates (for
// the run's own sensor, its [model.output] positions).
std::vector<SensorModelPlan> Plans(const CalibrationConfig& config,
                                   const plate::SensorOptions& model) {
  std::vector<SensorModelPlan> plans;
  for (std::size_t e = 0; e < config.experiments.size(); ++e) {
    const ExperimentConfig& x = config.experiments[e];
    auto same = [&](const SensorModelPlan& p) { return p.options.frequency_hz == x.frequency_hz; };
    auto it = std::find_if(plans.begin(), plans.end(), same);
    if (it == plans.end()) {
      SensorModelPlan plan;
      plan.options = model;
      plan.options.frequency_hz = x.frequency_hz;
      plan.options.load_cases.clear();
      plans.push_back(std::move(plan));
      it = plans.end() - 1;
    }
    plate::LoadCase load = x.load;
    load.output_positions = x.output_coordinates;
    it->options.load_cases.push_back(std::move(load));
    it->experiments.push_back(e);
  }
  return plans;
}

}  // namespace

std::vector<SensorModelPlan> SensorModels(const CalibrationConfig& config) {
  return Plans(config, config.model);
}

std::vector<SensorModelPlan> LowFidelitySensorModels(const CalibrationConfig& config) {
  return Plans(config, config.low_fidelity.value().model);
}

namespace config_internal {
namespace {

LengthUnit UnitKey(TableReader& t, std::string_view key, LengthUnit fallback) {
  return t.Choice<LengthUnit>(key, "unit").value_or(fallback);
}

// Experiment names go into component names, export file names and CSV columns.
bool GoodName(const std::string& name) {
  if (name.empty() || name.size() > 64 || name == "." || name == "..") return false;
  return std::all_of(name.begin(), name.end(), [](char ch) {
    return std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '-' || ch == '.';
  });
}

// The threshold schedules of every threshold or likelihood component, experiment by experiment.
void CollectThresholds(CalibrationConfig* c) {
  c->smc.thresholds.clear();
  for (const ExperimentConfig& x : c->experiments) {
    for (const MetricComponentConfig& component : x.metric.components) {
      if (KindOf(component) != ComponentKind::kIndicator) {
        c->smc.thresholds.push_back(component.threshold);
      }
    }
  }
}

// The experiment's sensor options (its load case and frequency on the [model] plate) must be
// valid; a failure is reported at the experiment's key that set the field.
void CheckSensorExperiment(const CalibrationConfig& c,
                           const ExperimentConfig& x,
                           const std::map<std::string, Source>& sources) {
  plate::SensorOptions one = c.model;
  one.load_cases = {x.load};
  one.frequency_hz = x.frequency_hz;
  ValidationError error;
  if (!one.IsValid(&error)) ThrowModelError(error, sources, x.line, c.path);
}

// Every component's export columns (d_<name>, eps_<name>: the full name, "<experiment>/<name>"
// with experiments, as export.cpp's Identifier writes it) must be its own: two names that differ
// only in case or punctuation ("fit-a", "fit_a"; experiment "a_b" with "c" and "a" with "b_c")
// would give two columns of one name, and a reader would take one for the other.
void CheckComponentColumns(const CalibrationConfig& c) {
  struct Seen {
    std::string name;
    int line;
  };
  std::map<std::string, Seen> columns;
  for (std::size_t e = 0; e < c.experiments.size(); ++e) {
    const ExperimentConfig& x = c.experiments[e];
    const std::vector<MetricComponentConfig>& components = x.metric.components;
    for (std::size_t k = 0; k < components.size(); ++k) {
      const MetricComponentConfig& component = components[k];
      const std::string name = x.ComponentPrefix() + ComponentName(component);
      const std::string column = ColumnKey(name);
      const auto [it, fresh] = columns.emplace(column, Seen{name, component.config_line});
      if (fresh) continue;
      const std::string table = x.metric.preset ? std::string("metric.preset")
                                                : "metric.component[" + std::to_string(k) + "]";
      const bool named = !component.name.empty();
      throw Error(ErrorKind::kConfig,
                  "component " + Excerpt(name) + " would share the export columns (d_" + column +
                      ") of component " + Excerpt(it->second.name) + " at line " +
                      std::to_string(it->second.line) +
                      ": names that differ only in case or punctuation are one column; " +
                      (named ? "rename one" : "give one a name"),
                  c.path,
                  component.config_line,
                  x.Key(e, table));
    }
  }
}

void ParseOne(TableReader& t,
              std::size_t index,
              CalibrationConfig* c,
              ExperimentConfig* x,
              std::map<std::string, Source> sources) {
  const bool sensor = c->simulator.kind == SimulatorKind::kSensor;
  if (x->line != 0) {
    if (auto l = t.Table("load")) {
      ParseLoadTable(*l, &x->load, &x->frequency_hz, &sources);
    }
    if (auto o = t.Table("output")) {
      if (!sensor) {
        o->Fail("", "an external simulator declares its outputs in [simulator.outputs]");
      }
      ParseOutputTable(*o, c->model.length, &x->load, &sources);
    }
  }
  if (sensor) {
    CheckSensorExperiment(*c, *x, sources);
    x->output_coordinates = x->load.output_positions;
  } else {
    x->output_coordinates = c->simulator.outputs.coordinates;
  }
  auto data = t.Table("data");
  if (!data) {
    throw Error(ErrorKind::kConfig,
                "missing required table [" + x->Key(index, "data") + "]",
                c->path,
                x->line != 0 ? x->line : 1,
                x->Key(index, "data"));
  }
  ParseDataTable(*data, sensor ? std::optional<double>(x->load.load_x) : std::nullopt, &x->data);
  auto metric = t.Table("metric");
  if (!metric) {
    throw Error(ErrorKind::kConfig,
                "missing required table [" + x->Key(index, "metric") + "]",
                c->path,
                x->line != 0 ? x->line : 1,
                x->Key(index, "metric"));
  }
  ParseMetricTable(*metric, x->data.position_unit, c->smc.num_waves, &x->metric);
}

}  // namespace

}  // namespace config_internal

// The name as an export column sees it (export.cpp's Identifier: lower case, each run of other
// characters one '_'): two experiments or components must differ there too, or their columns
// would collide.
std::string ColumnKey(const std::string& name) {
  std::string out;
  for (char ch : name) {
    if (std::isalnum(static_cast<unsigned char>(ch)) != 0) {
      out += static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    } else if (!out.empty() && out.back() != '_') {
      out += '_';
    }
  }
  while (!out.empty() && out.back() == '_') out.pop_back();
  return out;
}

namespace config_internal {

void RefuseExperimentPlaceholders(const std::vector<std::string>& argv,
                                  int line,
                                  const std::string& key,
                                  const std::string& path) {
  for (const std::string& arg : argv) {
    for (const char* placeholder : kExperimentPlaceholders) {
      if (arg.find(placeholder) != std::string::npos) {
        throw Error(ErrorKind::kConfig,
                    std::string("uses ") + placeholder +
                        ", which only [[experiment]] tables fill in (docs/simulators.md)",
                    path,
                    line,
                    key);
      }
    }
  }
}

void ParseDataTable(TableReader& t, std::optional<double> impact_default, DataConfig* data) {
  DataConfig& d = *data;
  const auto csv = t.String("csv");
  if (!csv || csv->empty()) t.Fail("csv", "missing required key (path of the measured CSV)");
  d.csv = *csv;
  d.position_column = t.String("position_column").value_or(d.position_column);
  d.displacement_column = t.String("displacement_column").value_or(d.displacement_column);
  if (d.position_column == d.displacement_column) {
    t.Fail("displacement_column", "must differ from position_column");
  }
  d.position_unit = UnitKey(t, "position_unit", d.position_unit);
  d.displacement_unit = UnitKey(t, "displacement_unit", d.displacement_unit);
  const double unit = MetresPer(d.position_unit);
  if (t.Has("window")) {
    const auto [lo, hi] = WindowKey(t, "window", unit);
    d.window_min = lo;
    d.window_max = hi;
  }
  d.normalise = t.Bool("normalise").value_or(d.normalise);

  if (auto g = t.Table("gaussian_extension")) {
    GaussianExtensionOptions& e = d.gaussian_extension;
    e.enabled = g->Bool("enabled").value_or(true);  // the table's presence asks for it
    // Default: the experiment's load position (the paper fits "centred at the shaker location").
    e.impact_position = impact_default.value_or(e.impact_position);
    if (const auto impact = g->Number("impact_position")) {
      if (!std::isfinite(*impact)) g->Fail("impact_position", "must be finite");
      e.impact_position = *impact * unit;
    }
    if (e.enabled && !g->Has("impact_position") && !impact_default) {
      g->Fail("impact_position",
              "missing required key: the default is the sensor's load position, and this run's "
              "simulator is not the sensor");
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
  t.Finish();
}

void ParseExperiments(TableReader& root,
                      CalibrationConfig* c,
                      const std::map<std::string, Source>& model_sources) {
  auto tables = root.Tables("experiment");
  c->experiments.clear();
  ExperimentConfig defaults;
  defaults.load = c->model.load_cases.front();
  defaults.frequency_hz = c->model.frequency_hz;
  if (tables.empty()) {
    // The shorthand: one experiment, unnamed, from the top-level tables. An external program
    // told about experiments it does not have would read the placeholders literally.
    RefuseExperimentPlaceholders(
        c->simulator.external.argv, c->simulator.argv_line, "simulator.argv", c->path);
    ExperimentConfig x = defaults;
    ParseOne(root, 0, c, &x, model_sources);
    c->experiments.push_back(std::move(x));
  } else {
    for (const char* shorthand : {"data", "metric"}) {
      if (root.Has(shorthand)) {
        root.Fail(shorthand,
                  std::string("[") + shorthand + "] is the shorthand for one experiment; with " +
                      "[[experiment]] tables give each its own [experiment." + shorthand + "]");
      }
    }
    std::map<std::string, int> lines;
    for (std::size_t e = 0; e < tables.size(); ++e) {
      TableReader& t = tables[e];
      ExperimentConfig x = defaults;
      x.line = t.line();
      const auto name = t.String("name");
      if (!name) t.Fail("name", "missing required key (a name for the experiment, e.g. \"45cm\")");
      if (!GoodName(*name)) {
        t.Fail("name",
               Excerpt(*name) +
                   " must be 1 to 64 letters, digits, '_', '-' or '.' (it names "
                   "files and columns)");
      }
      const auto [it, fresh] = lines.emplace(ColumnKey(*name), t.Line("name"));
      if (!fresh) {
        t.Fail("name",
               "experiment " + Excerpt(*name) + " is already defined at line " +
                   std::to_string(it->second) +
                   " (names that differ only in case or punctuation would share export columns)");
      }
      x.name = *name;
      ParseOne(t, e, c, &x, model_sources);
      t.Finish();
      c->experiments.push_back(std::move(x));
    }
  }
  // The model normalises every profile alike, as the data are normalised.
  const ExperimentConfig& first = c->experiments.front();
  for (std::size_t e = 1; e < c->experiments.size(); ++e) {
    const ExperimentConfig& x = c->experiments[e];
    if (x.data.normalise != first.data.normalise) {
      throw Error(ErrorKind::kConfig,
                  "must be the same in every experiment (the model normalises every profile "
                  "alike)",
                  c->path,
                  x.line,
                  x.Key(e, "data.normalise"));
    }
  }
  c->model.normalise = first.data.normalise;
  c->simulator.outputs.coordinates.clear();
  for (const ExperimentConfig& x : c->experiments) {
    c->simulator.outputs.coordinates.insert(c->simulator.outputs.coordinates.end(),
                                            x.output_coordinates.begin(),
                                            x.output_coordinates.end());
  }
  CheckComponentColumns(*c);
  CollectThresholds(c);
}

}  // namespace config_internal
}  // namespace combabc
