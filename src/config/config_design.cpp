// [design]: the grid of candidate experiments `combabc design` ranks (docs/config.md, "Design").
#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <thread>

#include "combabc/config/config.hpp"
#include "combabc/core/error.hpp"
#include "combabc/params/binary_space.hpp"
#include "config_reader.hpp"

namespace combabc {
namespace {

// The points of a scan window [from, to] every `spacing`, counted without building them.
double ScanPoints(double from, double to, double spacing) {
  return std::floor((to - from) / spacing + 1e-9) + 1.0;
}

std::string Gb(double bytes) {
  std::ostringstream os;
  os.precision(bytes < 1e8 ? 2 : 3);
  os << bytes / 1e9 << " GB";
  return os.str();
}

}  // namespace

std::vector<double> DesignScanPositions(double from, double to, double spacing) {
  std::vector<double> x;
  const auto n = static_cast<int>(ScanPoints(from, to, spacing)) - 1;
  for (int k = 0; k <= n; ++k) x.push_back(from + k * spacing);
  return x;
}

plate::SensorOptions DesignSensorOptions(const CalibrationConfig& c) {
  const DesignConfig& d = *c.design;
  plate::SensorOptions options = c.model;
  options.normalise = true;  // as the measured data are normalised
  options.load_cases.clear();
  const plate::LoadCase base = c.model.load_cases.front();
  for (double x : d.load_x) {
    for (double y : d.load_y_fraction) {
      for (const auto& [from, to] : d.scans) {
        for (double line : d.scan_y_fraction) {
          plate::LoadCase lc = base;
          lc.load_x = x;
          lc.load_y_fraction = y;
          lc.output_positions = DesignScanPositions(from, to, d.scan_spacing);
          lc.output_y_fraction = line;
          options.load_cases.push_back(std::move(lc));
        }
      }
    }
  }
  return options;
}

DesignMemory EstimateDesignMemory(const CalibrationConfig& c, double particles) {
  const DesignConfig& d = *c.design;
  double points = 0.0;  // over every candidate
  for (const auto& [from, to] : d.scans) points += ScanPoints(from, to, d.scan_spacing);
  points *=
      static_cast<double>(d.load_x.size() * d.load_y_fraction.size() * d.scan_y_fraction.size());
  const auto dimension = static_cast<double>(c.space.dimension);
  const unsigned cores = std::max(1U, std::thread::hardware_concurrency());
  const double threads = c.smc.threads > 0 ? c.smc.threads : cores;
  DesignMemory m;
  m.model = DesignSensorOptions(c).EstimatedMemoryBytes();
  // The batch of profiles and each candidate's copy of its columns (services/design.cpp), and
  // the population: its bits twice (the merging map's nodes, about 100 bytes each, and the
  // array) and its weights.
  m.profiles = particles * (16.0 * points + 2.0 * dimension + 120.0);
  // Per truth, the chosen experiments' summed log-likelihood of every particle; per thread, one
  // truth's; per truth, its bits' marginals.
  m.scoring = 8.0 * particles * (d.truths + threads) + 16.0 * d.truths * dimension;
  return m;
}

namespace config_internal {
namespace {

// Refuses, before anything is simulated, a [design] whose scan points exceed the sensor's output
// limit or whose memory estimate exceeds memory_limit_gb, at the key that asks for the larger
// share.
void CheckDesignSize(TableReader& t, const CalibrationConfig& c) {
  const DesignConfig& d = *c.design;
  double points = 0.0;
  for (const auto& [from, to] : d.scans) points += ScanPoints(from, to, d.scan_spacing);
  const double candidates =
      static_cast<double>(d.load_x.size() * d.load_y_fraction.size() * d.scan_y_fraction.size());
  if (points * candidates > static_cast<double>(plate::kMaxOutputPositions)) {
    std::ostringstream os;
    os.precision(3);
    os << "gives " << points * candidates << " scan points over the "
       << d.load_x.size() * d.load_y_fraction.size() * d.scan_y_fraction.size() * d.scans.size()
       << " candidates; the sensor takes at most " << plate::kMaxOutputPositions
       << " (a larger scan_spacing, fewer or shorter scans, or fewer loads)";
    t.Fail("scan_spacing", os.str());
  }
  // The design's population: every configuration of a small free-bit space, else the prior
  // draws (a posterior's size is checked when it is read, services/design.cpp). An invalid
  // space is refused later, at its own key.
  std::string why;
  if (!c.space.IsValid(&why)) return;
  const int free = BinarySpace(c.space).num_free();
  const double particles = free <= kDesignExactBits ? std::ldexp(1.0, free) : d.particles;
  const DesignMemory m = EstimateDesignMemory(c, particles);
  if (m.total() <= c.model.memory_limit_bytes) return;
  const bool sampled = free > kDesignExactBits;
  // Both the profiles and the scoring grow with the particles: a particles key the user set is
  // blamed before the truths it does not set.
  const char* key = m.model >= std::max(m.profiles, m.scoring)  ? "load_x"
                    : m.scoring > m.profiles && t.Has("truths") ? "truths"
                    : sampled && t.Has("particles")             ? "particles"
                    : m.scoring > m.profiles                    ? "truths"
                                                                : "scan_spacing";
  t.Fail(key,
         "the design would need about " + Gb(m.total()) + " of memory (limit " +
             Gb(c.model.memory_limit_bytes) + "): sensor " + Gb(m.model) + ", " +
             std::to_string(static_cast<long long>(particles)) + " profiles of " +
             std::to_string(static_cast<long long>(points * candidates)) + " scan points " +
             Gb(m.profiles) + ", scoring over " + std::to_string(d.truths) + " truths " +
             Gb(m.scoring) + "; fewer particles, truths or scan points, or raise memory_limit_gb " +
             "(docs/config.md, \"Limits\")");
}

}  // namespace

void ParseDesignSection(TableReader& root,
                        CalibrationConfig* c,
                        const std::map<std::string, Source>& model_sources) {
  auto t = root.Table("design");
  if (!t) return;
  DesignConfig d;
  d.line = t->line();
  const LengthUnit unit_name =
      t->Choice<LengthUnit>("position_unit", "unit").value_or(LengthUnit::kCentimetre);
  const double unit = MetresPer(unit_name);
  const double length = c->model.length;
  auto positions = [&](const char* key, std::vector<double>* out, double scale, double hi) {
    const auto values = t->Numbers(key);
    if (!values) return;
    if (values->empty()) t->Fail(key, "must not be empty");
    out->clear();
    for (double v : *values) {
      const double x = v * scale;
      if (!(x >= 0.0 && x <= hi)) {
        t->Fail(
            key,
            "entry " + std::to_string(v) + " lies outside [0, " + std::to_string(hi / scale) + "]");
      }
      out->push_back(x);
    }
  };
  if (!t->Has("load_x")) t->Fail("load_x", "missing required key (the load positions to try)");
  positions("load_x", &d.load_x, unit, length);
  positions("load_y_fraction", &d.load_y_fraction, 1.0, 1.0);
  positions("scan_y_fraction", &d.scan_y_fraction, 1.0, 1.0);
  if (const toml::node* scans = t->Raw("scan")) {
    const auto* list = scans->as_array();
    if (list == nullptr || list->empty()) t->Fail("scan", "must be a list of [from, to] windows");
    for (const toml::node& item : *list) {
      const auto* pair = item.as_array();
      const auto from = pair && pair->size() == 2 ? (*pair)[0].value<double>() : std::nullopt;
      const auto to = pair && pair->size() == 2 ? (*pair)[1].value<double>() : std::nullopt;
      if (!from || !to || !(*from < *to) || *from * unit < 0.0 ||
          *to * unit > length * (1 + 1e-12)) {
        t->FailAt(item,
                  t->Key("scan"),
                  "each window must be [from, to] with 0 <= from < to <= model.length");
      }
      d.scans.emplace_back(*from * unit, *to * unit);
    }
  } else {
    d.scans.emplace_back(0.0, length);  // the whole length, as the paper's section 6 suggests
  }
  if (const auto spacing = t->Number("scan_spacing")) {
    if (!(*spacing > 0.0) || *spacing * unit > length) {
      t->Fail("scan_spacing", "must be in (0, model.length]");
    }
    d.scan_spacing = *spacing * unit;
  }
  d.noise = t->NumberIn("noise", d.noise, 1e-9, 10.0);
  d.truths = t->IntegerIn("truths", d.truths, 2, 1000000);
  d.particles = t->IntegerIn("particles", d.particles, 1, 10000000);
  d.select = t->IntegerIn("select", d.select, 1, 1000);
  d.identified_margin = t->NumberIn("identified_margin", d.identified_margin, 0.0, 0.4999);
  const std::size_t candidates =
      d.load_x.size() * d.load_y_fraction.size() * d.scans.size() * d.scan_y_fraction.size();
  if (candidates > plate::kMaxLoadCases) {
    t->Fail("load_x",
            "the grid gives " + std::to_string(candidates) + " candidates; at most " +
                std::to_string(plate::kMaxLoadCases));
  }
  // A load of amplitude 0 deflects nothing: every candidate's profile would be 0 and every gain
  // 0, a ranking that says nothing. Refused at the amplitude the design loads with.
  if (c->model.load_cases.front().load_force == 0.0) {
    const auto it = model_sources.find("load_force");
    throw Error(ErrorKind::kConfig,
                "is 0: a load of amplitude 0 deflects nothing, so no candidate experiment could "
                "tell one configuration from another; [design] loads with this amplitude",
                c->path,
                it != model_sources.end() ? it->second.line : d.line,
                it != model_sources.end() ? it->second.key : "model.load.amplitude");
  }
  c->design = std::move(d);
  CheckDesignSize(*t, *c);
  t->Finish();
}

}  // namespace config_internal
}  // namespace combabc
