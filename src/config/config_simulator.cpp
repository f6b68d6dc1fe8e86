// [simulator]: which simulator the run calibrates. "sensor" (the default) is the built-in plate
// configured by [model]; "command" and "worker" are external programs (docs/simulators.md) that
// declare their binary parameters ([simulator.bits]) and outputs ([simulator.outputs]) here.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <string>

#include "combabc/config/config.hpp"
#include "combabc/core/bounded_read.hpp"
#include "combabc/core/error.hpp"
#include "combabc/data/csv_reader.hpp"
#include "combabc/params/binary_space.hpp"
#include "combabc/plate/assembly/clamp_pattern.hpp"
#include "config_reader.hpp"

namespace combabc::config_internal {
namespace {

// Largest output vector an external simulator may declare (as the sensor's kMaxOutputPositions).
constexpr int kMaxOutputs = 1000000;

bool ParseNumber(std::string_view text, double* value) {
  while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) text.remove_prefix(1);
  while (!text.empty() && (text.back() == ' ' || text.back() == '\t' || text.back() == '\r')) {
    text.remove_suffix(1);
  }
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), *value);
  return ec == std::errc() && end == text.data() + text.size() && !text.empty();
}

// coordinates_csv: one coordinate per row in its first column, in the dialect of the data CSV
// (data/csv_reader.hpp); a first row that is not a number is a header. Errors name the file and
// line.
std::vector<double> ReadCoordinatesCsv(const std::string& path) {
  const std::string text =
      ReadBoundedFile(path, std::size_t{64} << 20, "coordinates file", ErrorKind::kData);
  CsvReader csv(text, path);
  std::vector<double> values;
  for (bool first = true; csv.Next(); first = false) {
    const std::string& cell = csv.cells().front();
    double v = 0.0;
    if (!ParseNumber(cell, &v)) {
      if (first) continue;  // header
      throw Error(
          ErrorKind::kData, Excerpt(cell) + " is not a number", path, csv.line(), "coordinate", 1);
    }
    if (!std::isfinite(v)) {
      throw Error(ErrorKind::kData, "must be finite", path, csv.line(), "coordinate", 1);
    }
    values.push_back(v);
  }
  return values;
}

void ParseOutputs(TableReader& s, const std::string& directory, SimulatorOutputs* outputs) {
  auto o = s.Table("outputs");
  if (!o) {
    s.Fail("outputs", "missing required table [" + s.Key("outputs") + "] (name and coordinates)");
  }
  SimulatorOutputs& out = *outputs;
  out.name = o->String("name").value_or(out.name);
  if (out.name.empty()) o->Fail("name", "must not be empty");
  const bool listed = o->Has("coordinates");
  if (listed == o->Has("coordinates_csv")) {
    o->Fail("coordinates", "give exactly one of coordinates or coordinates_csv");
  }
  std::string key = "coordinates";
  if (listed) {
    out.coordinates = *o->Numbers("coordinates");
  } else {
    key = "coordinates_csv";
    const std::string file = *o->String("coordinates_csv");
    if (file.empty()) o->Fail(key, "must not be empty");
    out.coordinates = ReadCoordinatesCsv(ResolvePath(directory, file));
  }
  if (out.coordinates.empty()) o->Fail(key, "must hold at least one coordinate");
  if (out.size() > kMaxOutputs) {
    o->Fail(
        key,
        "has " + std::to_string(out.size()) + " entries; at most " + std::to_string(kMaxOutputs));
  }
  for (std::size_t k = 0; k < out.coordinates.size(); ++k) {
    if (!std::isfinite(out.coordinates[k])) o->Fail(key, "must be finite");
    if (k > 0 && !(out.coordinates[k] > out.coordinates[k - 1])) {
      o->Fail(key, "must be strictly increasing (entry " + std::to_string(k) + ")");
    }
  }
  o->Finish();
}

// The bit names of [<simulator>.bits]; where their number is set: *key and *line. No table (or
// count = 0) is a simulator without bits: its parameters are all [parameters.<name>] (ParseConfig
// checks that it has some).
std::vector<std::string> ParseBits(TableReader& s, std::string* key, int* line) {
  auto b = s.Table("bits");
  if (!b) {
    *key = s.Key("bits");
    *line = s.line();
    return {};
  }
  std::vector<std::string> names = b->Strings("names").value_or(std::vector<std::string>{});
  const auto count = b->Integer("count");
  if (!count && names.empty()) b->Fail("count", "missing required key (or give names)");
  if (count && (*count < 0 || *count > kMaxBits)) {
    b->Fail("count", "must be in [0, " + std::to_string(kMaxBits) + "]");
  }
  if (names.empty()) {
    for (int k = 1; k <= *count; ++k) names.push_back("bit " + std::to_string(k));
  } else if (count && *count != static_cast<std::int64_t>(names.size())) {
    b->Fail("names",
            "has " + std::to_string(names.size()) + " names; count is " + std::to_string(*count));
  }
  if (static_cast<int>(names.size()) > kMaxBits) {
    b->Fail("names", "has more than " + std::to_string(kMaxBits) + " names");
  }
  std::set<std::string> seen;
  for (const std::string& n : names) {
    if (n.empty()) b->Fail("names", "a name is empty");
    if (!seen.insert(n).second) b->Fail("names", Excerpt(n) + " appears twice");
  }
  const std::string_view bits_key = count ? "count" : "names";
  *key = b->Key(bits_key);
  *line = b->Line(bits_key);
  b->Finish();
  return names;
}

double Seconds(TableReader& s, std::string_view key, double fallback) {
  return s.NumberIn(key, fallback, 0.0, 1e7);
}

// A command's or worker's program and hand-over ([simulator] or [simulator.low_fidelity]).
void ParseExternal(TableReader& s, const std::string& directory, SimulatorConfig* sim) {
  ExternalSimulatorOptions& e = sim->external;
  const auto argv = s.Strings("argv");
  if (!argv || argv->empty() || argv->front().empty()) {
    s.Fail("argv",
           "missing required key: the program and its arguments, e.g. "
           "[\"python3\", \"{config_dir}/model.py\", \"{params}\"]");
  }
  e.argv = *argv;
  sim->argv_line = s.Line("argv");
  e.timeout_s = Seconds(s, "timeout", e.timeout_s);
  e.retries = s.IntegerIn("retries", e.retries, 0, 100);
  if (sim->kind == SimulatorKind::kCommand) {
    e.params = s.Choice<Transport>("params", "parameter hand-over").value_or(e.params);
    if (e.params == Transport::kStdout) s.Fail("params", "must be \"file\" or \"stdin\"");
    e.params_format = s.Choice<DataFormat>("params_format", "format").value_or(e.params_format);
    e.results = s.Choice<Transport>("results", "result hand-over").value_or(e.results);
    if (e.results == Transport::kStdin) s.Fail("results", "must be \"stdout\" or \"file\"");
    e.results_format = s.Choice<DataFormat>("results_format", "format").value_or(e.results_format);
  } else {
    e.startup_timeout_s = Seconds(s, "startup_timeout", e.startup_timeout_s);
  }
  e.config_directory = directory;
}

// The options the program is called with once its bits and outputs are known, checked.
void FinishExternal(TableReader& s,
                    const std::vector<std::string>& bit_names,
                    SimulatorConfig* sim) {
  ExternalSimulatorOptions& e = sim->external;
  e.bit_names = bit_names;
  e.output_size = sim->outputs.size();
  // The work folder is the run's (set by the services layer); a placeholder passes IsValid here.
  e.work_directory = ".";
  ValidationError error;
  if (!e.IsValid(sim->kind, &error)) {
    const std::map<std::string, std::string> keys = {
        {"argv", "argv"}, {"params", "params"}, {"results", "results"}};
    const auto it = keys.find(error.field);
    s.Fail(it != keys.end() ? it->second : "kind", error.Detail());
  }
}

}  // namespace

void ParseSimulatorSection(TableReader& root, CalibrationConfig* c) {
  SimulatorConfig& sim = c->simulator;
  auto s = root.Table("simulator");
  sim.kind = s ? s->Choice<SimulatorKind>("kind", "simulator kind").value_or(sim.kind)
               : SimulatorKind::kSensor;
  if (sim.kind == SimulatorKind::kSensor) {
    // The built-in plate declares itself: one bit per clamp, its laser positions as outputs.
    sim.outputs.name = "displacement";
    // The coordinates: every experiment's output positions (ParseExperiments).
    c->space.names.clear();
    for (int k = 1; k <= plate::ClampPattern::Size(c->model.clamps_per_edge); ++k) {
      c->space.names.push_back("clamp " + std::to_string(k));
    }
    if (s) {
      s->Raw("low_fidelity");  // ParseLowFidelitySection's, once the experiments are known
      s->Finish();             // any other key is for external simulators: reported as unknown
    }
    return;
  }
  // [model] configures a cheap sensor too (whatever the expensive simulator is).
  auto low = s->Table("low_fidelity");
  const bool cheap_sensor =
      low &&
      low->Choice<SimulatorKind>("kind", "simulator kind").value_or(SimulatorKind::kSensor) ==
          SimulatorKind::kSensor;
  if (root.Has("model") && !cheap_sensor) {
    root.Fail("model",
              "[model] configures the built-in sensor; a simulator of kind = \"" +
                  std::string(ToString(sim.kind)) +
                  "\" declares its bits and outputs in [simulator.bits] and [simulator.outputs] "
                  "([model] is for the built-in sensor, the run's or [simulator.low_fidelity]'s)");
  }
  ParseExternal(*s, c->directory, &sim);
  c->space.names = ParseBits(*s, &c->bits_key, &c->bits_line);
  ParseOutputs(*s, c->directory, &sim.outputs);
  FinishExternal(*s, c->space.names, &sim);
  s->Finish();
}

namespace {

std::string Metres(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%g m", x);
  return text;
}

// The cheap sensor: [model] with [simulator.low_fidelity.model] over it, on the run's bits,
// reals and experiments. Returns each experiment's output coordinates (the expensive ones').
std::vector<std::vector<double>> ParseCheapSensor(TableReader& t, CalibrationConfig* c) {
  LowFidelityConfig& low = *c->low_fidelity;
  if (t.Has("memory_limit_gb")) {
    t.Fail("memory_limit_gb", "is a top-level key: it bounds the whole run, both models");
  }
  if (auto m = t.Table("model")) {
    for (const char* key : {"load", "output"}) {
      if (m->Has(key)) {
        m->Fail(key,
                "the cheap sensor simulates the run's experiments: their loads, at the expensive "
                "simulator's output coordinates");
      }
    }
  }
  // ParseModelSection reads [simulator.low_fidelity.model] over a copy of the run's [model].
  CalibrationConfig over;
  over.path = c->path;
  over.model = c->model;
  std::map<std::string, Source> sources;
  ParseModelSection(t, &over, &sources);
  low.model = over.model;
  low.model.normalise = c->model.normalise;
  low.simulator.outputs.name = c->simulator.outputs.name;
  const int clamps = plate::ClampPattern::Size(low.model.clamps_per_edge);
  if (clamps != c->space.dimension) {
    const auto set = sources.find("clamps_per_edge");
    throw Error(ErrorKind::kConfig,
                "the cheap sensor has " + std::to_string(clamps) +
                    " clamps (2 x clamps per edge); the run has " +
                    std::to_string(c->space.dimension) +
                    " bits: the cheap simulator takes the same bits",
                c->path,
                set != sources.end() ? set->second.line : t.line(),
                set != sources.end() ? set->second.key : t.prefix());
  }
  for (const ContinuousParameter& r : c->reals) {
    if (!plate::FindSensorVariationField(r.name)) {
      t.Fail("kind",
             "the cheap sensor has no continuous parameter " + Excerpt(r.name) + " ([parameters." +
                 r.name + "]): the cheap simulator takes the run's reals");
    }
  }
  std::vector<std::vector<double>> coordinates;
  for (const ExperimentConfig& x : c->experiments) {
    for (double y : x.output_coordinates) {
      if (!(y >= 0.0 && y <= low.model.length)) {
        t.Fail("kind",
               "the expensive simulator's output at " + Metres(y) +
                   " lies off the cheap sensor's plate (0 to " + Metres(low.model.length) + ")");
      }
    }
    coordinates.push_back(x.output_coordinates);
  }
  for (const SensorModelPlan& plan : LowFidelitySensorModels(*c)) {
    ValidationError error;
    if (!plan.options.IsValid(&error)) ThrowModelError(error, sources, t.line(), c->path);
  }
  return coordinates;
}

}  // namespace

void ParseLowFidelitySection(TableReader& root, CalibrationConfig* c) {
  auto s = root.Table("simulator");
  auto t = s ? s->Table("low_fidelity") : std::nullopt;
  if (!t) return;
  c->low_fidelity.emplace();
  LowFidelityConfig& low = *c->low_fidelity;
  low.line = t->line();
  SimulatorConfig& sim = low.simulator;
  sim.kind = t->Choice<SimulatorKind>("kind", "simulator kind").value_or(SimulatorKind::kSensor);
  std::vector<std::vector<double>> cheap;  // each experiment's cheap output coordinates
  std::string outputs_key = "kind";
  if (sim.kind == SimulatorKind::kSensor) {
    cheap = ParseCheapSensor(*t, c);
  } else {
    ParseExternal(*t, c->directory, &sim);
    std::string bits_key;
    int bits_line = 0;
    const std::vector<std::string> names = ParseBits(*t, &bits_key, &bits_line);
    if (static_cast<int>(names.size()) != c->space.dimension) {
      throw Error(ErrorKind::kConfig,
                  "declares " + std::to_string(names.size()) + " bits; the run has " +
                      std::to_string(c->space.dimension) +
                      ": the cheap simulator takes the same bits",
                  c->path,
                  bits_line,
                  bits_key);
    }
    ParseOutputs(*t, c->directory, &sim.outputs);
    FinishExternal(*t, names, &sim);
    for (const ContinuousParameter& r : c->reals) sim.external.real_names.push_back(r.name);
    if (c->experiments.front().line == 0) {
      RefuseExperimentPlaceholders(sim.external.argv, sim.argv_line, t->Key("argv"), c->path);
    }
    cheap.assign(c->experiments.size(), sim.outputs.coordinates);
    outputs_key = "outputs";
  }
  // Every expensive output stands for the cheap output of its experiment at its coordinate.
  constexpr double kTolerance = 1e-9;  // metres
  int offset = 0;
  for (std::size_t e = 0; e < c->experiments.size(); ++e) {
    const ExperimentConfig& x = c->experiments[e];
    const std::vector<double>& mine = cheap[e];
    for (double y : x.output_coordinates) {
      auto it = std::lower_bound(mine.begin(), mine.end(), y - kTolerance);
      if (it == mine.end() || *it > y + kTolerance) {
        t->Fail(outputs_key,
                "has no output at " + Metres(y) +
                    (x.name.empty() ? "" : " (experiment " + Excerpt(x.name) + ")") +
                    ", where the expensive simulator has one: every expensive output coordinate "
                    "must be among the cheap simulator's (to 1e-9 m)");
      }
      low.output_map.push_back(offset + static_cast<int>(it - mine.begin()));
    }
    offset += static_cast<int>(mine.size());
  }
  t->Finish();
}

}  // namespace combabc::config_internal
