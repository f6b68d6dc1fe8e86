// [simulator]: which simulator the run calibrates. "sensor" (the default) is the built-in plate
// configured by [model]; "command" and "worker" are external programs (docs/simulators.md) that
// declare their binary parameters ([simulator.bits]) and outputs ([simulator.outputs]) here.
#include <charconv>
#include <cmath>
#include <map>
#include <set>
#include <string>

#include "combabc/config/config.hpp"
#include "combabc/core/bounded_read.hpp"
#include "combabc/core/error.hpp"
#include "combabc/data/csv_reader.hpp"
#include "combabc/params/binary_space.hpp"
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

void ParseOutputs(TableReader& s, CalibrationConfig* c) {
  auto o = s.Table("outputs");
  if (!o) s.Fail("outputs", "missing required table [simulator.outputs] (name and coordinates)");
  SimulatorOutputs& out = c->simulator.outputs;
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
    out.coordinates = ReadCoordinatesCsv(ResolvePath(c->directory, file));
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

void ParseBits(TableReader& s, CalibrationConfig* c) {
  auto b = s.Table("bits");
  if (!b) s.Fail("bits", "missing required table [simulator.bits] (count or names)");
  std::vector<std::string> names = b->Strings("names").value_or(std::vector<std::string>{});
  const auto count = b->Integer("count");
  if (!count && names.empty()) b->Fail("count", "missing required key (or give names)");
  if (count && (*count < 1 || *count > kMaxBits)) {
    b->Fail("count", "must be in [1, " + std::to_string(kMaxBits) + "]");
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
  c->space.names = names;
  const std::string_view bits_key = count ? "count" : "names";
  c->bits_key = b->Key(bits_key);
  c->bits_line = b->Line(bits_key);
  b->Finish();
}

double Seconds(TableReader& s, std::string_view key, double fallback) {
  return s.NumberIn(key, fallback, 0.0, 1e7);
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
    for (int k = 1; k <= 2 * c->model.clamps_per_edge; ++k) {
      c->space.names.push_back("clamp " + std::to_string(k));
    }
    if (s) s->Finish();  // any other key is for external simulators: reported as unknown
    return;
  }
  if (root.Has("model")) {
    root.Fail("model",
              "[model] configures the built-in sensor; a simulator of kind = \"" +
                  std::string(ToString(sim.kind)) +
                  "\" declares its bits and outputs in [simulator.bits] and [simulator.outputs]");
  }
  ExternalSimulatorOptions& e = sim.external;
  const auto argv = s->Strings("argv");
  if (!argv || argv->empty() || argv->front().empty()) {
    s->Fail("argv",
            "missing required key: the program and its arguments, e.g. "
            "[\"python3\", \"{config_dir}/model.py\", \"{params}\"]");
  }
  e.argv = *argv;
  sim.argv_line = s->Line("argv");
  e.timeout_s = Seconds(*s, "timeout", e.timeout_s);
  e.retries = s->IntegerIn("retries", e.retries, 0, 100);
  if (sim.kind == SimulatorKind::kCommand) {
    e.params = s->Choice<Transport>("params", "parameter hand-over").value_or(e.params);
    if (e.params == Transport::kStdout) s->Fail("params", "must be \"file\" or \"stdin\"");
    e.params_format = s->Choice<DataFormat>("params_format", "format").value_or(e.params_format);
    e.results = s->Choice<Transport>("results", "result hand-over").value_or(e.results);
    if (e.results == Transport::kStdin) s->Fail("results", "must be \"stdout\" or \"file\"");
    e.results_format = s->Choice<DataFormat>("results_format", "format").value_or(e.results_format);
  } else {
    e.startup_timeout_s = Seconds(*s, "startup_timeout", e.startup_timeout_s);
  }
  ParseBits(*s, c);
  ParseOutputs(*s, c);
  e.bit_names = c->space.names;
  e.output_size = sim.outputs.size();
  e.config_directory = c->directory;
  // The work folder is the run's (set by the services layer); a placeholder passes IsValid here.
  e.work_directory = ".";
  std::string why;
  if (!e.IsValid(sim.kind, &why)) {
    const std::string text = why.substr(why.find("::") + 2);
    const std::string field = text.substr(0, text.find_first_of(" ="));
    const std::map<std::string, std::string> keys = {
        {"argv", "argv"}, {"params", "params"}, {"results", "results"}};
    const auto it = keys.find(field);
    s->Fail(it != keys.end() ? it->second : "kind", text);
  }
  s->Finish();
}

}  // namespace combabc::config_internal
