// [design]: the grid of candidate experiments `combabc design` ranks (docs/config.md, "Design").
#include <string>

#include "combabc/config/config.hpp"
#include "combabc/core/error.hpp"
#include "config_reader.hpp"

namespace combabc::config_internal {

void ParseDesignSection(TableReader& root, CalibrationConfig* c) {
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
  t->Finish();
  c->design = std::move(d);
}

}  // namespace combabc::config_internal
