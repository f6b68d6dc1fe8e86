// [model]: the sensor simulator's options (combabc::plate::SensorOptions), in SI units.
#include <cmath>
#include <limits>
#include <map>
#include <sstream>
#include <string>

#include "combabc/config/config.hpp"
#include "combabc/core/error.hpp"
#include "config_reader.hpp"

namespace combabc::config_internal {
namespace {

// Reads an optional strictly positive finite number.
void Positive(TableReader& t,
              std::string_view key,
              double* value,
              std::map<std::string, Source>* sources,
              const std::string& field) {
  if (const auto v = t.Number(key)) {
    if (!(*v > 0.0) || !std::isfinite(*v)) t.Fail(key, "must be finite and > 0");
    *value = *v;
    (*sources)[field] = {t.Key(key), t.Line(key)};
  }
}

void InRange(TableReader& t,
             std::string_view key,
             double lo,
             double hi,
             double* value,
             std::map<std::string, Source>* sources,
             const std::string& field) {
  if (t.Has(key)) (*sources)[field] = {t.Key(key), t.Line(key)};
  *value = t.NumberIn(key, *value, lo, hi);
}

std::string Number(double x) {
  std::ostringstream out;
  out << x;
  return out.str();
}

// The config key of a SensorOptions field, for fields the user did not set (their line is the
// [model] table's). Layer fields are "layers[k]::name".
std::string ModelKeyOf(const std::string& field) {
  static const std::map<std::string, std::string> keys = {
      {"length", "model.length"},
      {"width", "model.width"},
      {"layers", "model.layer"},
      {"theory", "model.theory"},
      {"foundation_stiffness", "model.foundation_stiffness"},
      {"foundation_loss_factor", "model.foundation_loss_factor"},
      {"clamps_per_edge", "model.clamps.per_edge"},
      {"fixed_support", "model.clamps.fixed_support"},
      {"load_force", "model.load.amplitude"},
      {"load_x", "model.load.x"},
      {"load_y_fraction", "model.load.y_fraction"},
      {"load_patch_length", "model.load.patch_length"},
      {"load_patch_width", "model.load.patch_width"},
      {"frequency_hz", "model.load.frequency"},
      {"output_positions", "model.output.positions"},
      {"output_y_fraction", "model.output.y_fraction"},
      {"elements_per_section", "model.mesh.elements_per_section"},
      {"elements_across_width", "model.mesh.elements_across_width"},
      {"element_order", "model.mesh.element_order"},
      {"memory_limit_bytes", "memory_limit_gb"},
  };
  if (field.rfind("layers[", 0) == 0) {
    const std::size_t close = field.find(']');
    std::string name = field.substr(close + 3);  // after "]::"
    if (name == "youngs_modulus") name = "young_modulus";
    return "model.layer" + field.substr(6, close - 5) + "." + name;
  }
  const auto it = keys.find(field);
  return it != keys.end() ? it->second : "model";
}

// Reports a failed SensorOptions::IsValid at the config key the user wrote (or would write), in
// the config's words: "file:line: model.load.x: is 1.2; must lie on the plate, in [0, 0.9] m".
// C++ field names never reach the user.
}  // namespace

[[noreturn]] void ThrowModelError(const ValidationError& error,
                                  const std::map<std::string, Source>& sources,
                                  int model_line,
                                  const std::string& path) {
  const std::string& field = error.field;
  // output_positions[12] and output_positions.size() are both set by positions or spacing.
  std::string base = field;
  if (base.rfind("output_positions", 0) == 0) base = "output_positions";
  const auto it = sources.find(base);
  const bool set_by_user = it != sources.end();
  const std::string key = set_by_user ? it->second.key : ModelKeyOf(base);
  const int line = set_by_user ? it->second.line : model_line;
  const std::string& value = error.value;
  const std::string constraint = "; " + error.constraint;
  std::string detail;
  if (field.rfind("output_positions[", 0) == 0) {
    detail = "entry " + field.substr(17, field.find(']') - 17) + " is " + value + constraint;
  } else if (field == "output_positions.size()") {
    detail = "gives " + value + " positions" + constraint;
  } else if (field == "memory_limit_bytes") {  // bytes inside, GB in the config
    detail =
        "is " + Number(std::stod(value) / 1e9) + (set_by_user ? "" : " (the default)") + constraint;
  } else {
    detail = "is " + value + (set_by_user ? "" : " (the default)") + constraint;
  }
  if (error.constraint.find("of memory") != std::string::npos) {
    // "Lower it" would tell a user to lower the very limit that is too low.
    detail += field == "memory_limit_bytes"
                  ? "; raise it, or coarsen [model.mesh] (docs/config.md, \"Limits\")"
                  : "; lower it or raise memory_limit_gb (docs/config.md, \"Limits\")";
  }
  throw Error(ErrorKind::kConfig, detail, path, line, key);
}

namespace {

plate::Support SupportKey(TableReader& t, std::string_view key, plate::Support fallback) {
  return t.Choice<plate::Support>(key, "support").value_or(fallback);
}

plate::Layer ParseLayer(TableReader& t, int index, std::map<std::string, Source>* sources) {
  plate::Layer layer;
  // SensorOptions::IsValid names layer fields "layers[k]::youngs_modulus" (the C++ names).
  const std::string field = "layers[" + std::to_string(index) + "]::";
  Note(*sources, field + "thickness", t, "thickness");
  Note(*sources, field + "youngs_modulus", t, "young_modulus");
  Note(*sources, field + "density", t, "density");
  Note(*sources, field + "poisson_ratio", t, "poisson_ratio");
  Note(*sources, field + "loss_factor", t, "loss_factor");
  for (const char* required : {"thickness", "young_modulus", "density"}) {
    if (!t.Has(required)) t.Fail(required, "missing required key");
  }
  std::map<std::string, Source> unused;
  Positive(t, "thickness", &layer.thickness, &unused, "");
  Positive(t, "young_modulus", &layer.youngs_modulus, &unused, "");
  Positive(t, "density", &layer.density, &unused, "");
  if (const auto nu = t.Number("poisson_ratio")) {
    if (!(*nu > -1.0 && *nu < 0.5)) t.Fail("poisson_ratio", "must be in (-1, 0.5)");
    layer.poisson_ratio = *nu;
  }
  layer.loss_factor = t.NumberIn("loss_factor", layer.loss_factor, 0.0, kHuge);
  t.Finish();
  return layer;
}

}  // namespace

void ParseLoadTable(TableReader& l,
                    plate::LoadCase* c,
                    double* frequency_hz,
                    std::map<std::string, Source>* sources) {
  if (l.Has("x")) (*sources)["load_x"] = {l.Key("x"), l.Line("x")};
  c->load_x = l.NumberIn("x", c->load_x, 0.0, kHuge);
  InRange(l, "y_fraction", 0.0, 1.0, &c->load_y_fraction, sources, "load_y_fraction");
  Note(*sources, "load_force", l, "amplitude");
  if (const auto force = l.Number("amplitude")) {
    if (!std::isfinite(*force)) l.Fail("amplitude", "must be finite");
    c->load_force = *force;
  }
  InRange(l, "frequency", 0.0, kHuge, frequency_hz, sources, "frequency_hz");
  const auto type = l.String("type");
  if (type && *type != "point" && *type != "patch") {
    l.Fail("type", "unknown load type " + Excerpt(*type) + "; expected \"point\" or \"patch\"");
  }
  InRange(l, "patch_length", 0.0, kHuge, &c->load_patch_length, sources, "load_patch_length");
  InRange(l, "patch_width", 0.0, kHuge, &c->load_patch_width, sources, "load_patch_width");
  if (type && *type == "point") {
    if (l.Has("patch_length") || l.Has("patch_width")) {
      l.Fail("type", "a point load takes no patch_length / patch_width");
    }
    c->load_patch_length = 0.0;
    c->load_patch_width = 0.0;
  } else if (type && (c->load_patch_length <= 0.0 || c->load_patch_width <= 0.0)) {
    l.Fail("type", "a patch load needs patch_length and patch_width > 0");
  }
  l.Finish();
}

void ParseOutputTable(TableReader& o,
                      double length,
                      plate::LoadCase* c,
                      std::map<std::string, Source>* sources) {
  if (o.Has("positions") && o.Has("spacing")) {
    o.Fail("spacing", "give either positions or spacing, not both");
  }
  if (const auto positions = o.Numbers("positions")) {
    if (positions->empty()) o.Fail("positions", "must not be empty");
    if (positions->size() > plate::kMaxOutputPositions) {
      o.Fail("positions",
             "has " + std::to_string(positions->size()) + " entries; at most " +
                 std::to_string(plate::kMaxOutputPositions));
    }
    for (std::size_t k = 1; k < positions->size(); ++k) {
      if (!((*positions)[k] > (*positions)[k - 1])) {
        o.Fail("positions", "must be strictly increasing (entry " + std::to_string(k) + ")");
      }
    }
    c->output_positions = *positions;
    (*sources)["output_positions"] = {o.Key("positions"), o.Line("positions")};
  }
  if (const auto spacing = o.Number("spacing")) {
    if (!(*spacing > 0.0) || *spacing > length) {
      o.Fail("spacing", "must be in (0, model.length]");
    }
    // 0, h, 2h, ... up to the length (inclusive within rounding). The count is checked as a
    // double before the conversion (a tiny spacing would overflow an int, or exhaust memory).
    const double intervals = std::floor(length / *spacing + 1e-9);
    if (!(intervals + 1 <= static_cast<double>(plate::kMaxOutputPositions))) {
      o.Fail("spacing",
             "gives " + Number(intervals + 1) + " output positions; at most " +
                 std::to_string(plate::kMaxOutputPositions) + " (use a larger spacing)");
    }
    const auto n = static_cast<int>(intervals);
    c->output_positions.clear();
    for (int k = 0; k <= n; ++k) c->output_positions.push_back(k * *spacing);
    (*sources)["output_positions"] = {o.Key("spacing"), o.Line("spacing")};
  }
  InRange(o, "y_fraction", 0.0, 1.0, &c->output_y_fraction, sources, "output_y_fraction");
  o.Finish();
}

void ParseModelSection(TableReader& root,
                       CalibrationConfig* config,
                       std::map<std::string, Source>* model_sources) {
  plate::SensorOptions& m = config->model;
  std::map<std::string, Source>& sources = *model_sources;  // SensorOptions field -> config key
  // The memory budget is a top-level key: it bounds the whole run, the sampler's buffers too.
  if (root.Has("memory_limit_gb")) {
    Note(sources, "memory_limit_bytes", root, "memory_limit_gb");
    m.memory_limit_bytes = root.NumberIn("memory_limit_gb", 0.0, 0.01, 1e4) * 1e9;
  }
  auto t = root.Table("model");
  if (t) {
    sources[""] = {t->prefix(), t->line()};
    Positive(*t, "length", &m.length, &sources, "length");
    Positive(*t, "width", &m.width, &sources, "width");
    m.theory = t->Choice<plate::PlateTheory>("theory", "plate theory").value_or(m.theory);
    InRange(*t,
            "foundation_stiffness",
            0.0,
            kHuge,
            &m.foundation_stiffness,
            &sources,
            "foundation_stiffness");
    InRange(*t,
            "foundation_loss_factor",
            0.0,
            kHuge,
            &m.foundation_loss_factor,
            &sources,
            "foundation_loss_factor");

    auto layers = t->Tables("layer");
    if (!layers.empty()) {
      m.layers.clear();
      for (TableReader& lt : layers) {
        m.layers.push_back(ParseLayer(lt, static_cast<int>(m.layers.size()), &sources));
      }
      sources["layers"] = {t->Key("layer"), t->Line("layer")};
    }

    if (auto c = t->Table("clamps")) {
      const bool per_edge_given = c->Has("per_edge");
      Note(sources, "clamps_per_edge", *c, "per_edge");
      m.clamps_per_edge = c->IntegerIn("per_edge", m.clamps_per_edge, 1, plate::kMaxClampsPerEdge);
      if (const auto section = c->Number("section_length")) {
        // An alternative way to state the layout; it must tile the length exactly.
        if (!(*section > 0.0) || !std::isfinite(*section)) {
          c->Fail("section_length", "must be finite and > 0");
        }
        // Checked as a double before the conversion to int (which could overflow).
        const double sections = m.length / *section;
        if (!(sections <= plate::kMaxClampsPerEdge)) {
          c->Fail("section_length",
                  "gives " + Number(sections) + " sections per edge; at most " +
                      std::to_string(plate::kMaxClampsPerEdge));
        }
        const auto rounded = std::lround(sections);
        if (rounded < 1 || std::abs(sections - static_cast<double>(rounded)) > 1e-6) {
          c->Fail("section_length", "must divide model.length into a whole number of sections");
        }
        if (per_edge_given && rounded != m.clamps_per_edge) {
          c->Fail("section_length",
                  "disagrees with per_edge (length / section_length = " + std::to_string(rounded) +
                      ")");
        }
        m.clamps_per_edge = static_cast<int>(rounded);
        Note(sources, "clamps_per_edge", *c, "section_length");
      }
      const std::string_view bits_key =
          c->Has("per_edge") || !c->Has("section_length") ? "per_edge" : "section_length";
      config->bits_key = c->Key(bits_key);
      config->bits_line = c->Line(bits_key);
      m.fixed_support = SupportKey(*c, "fixed_support", m.fixed_support);
      if (m.fixed_support == plate::Support::kFree) {
        c->Fail("fixed_support", "must be \"clamped\" or \"simply_supported\"");
      }
      c->Finish();
    }

    if (auto e = t->Table("short_edges")) {
      m.short_edge_start = SupportKey(*e, "start", m.short_edge_start);
      m.short_edge_end = SupportKey(*e, "end", m.short_edge_end);
      e->Finish();
    }

    if (auto l = t->Table("load")) {
      ParseLoadTable(*l, &m.load_cases[0], &m.frequency_hz, &sources);
    }
    if (auto o = t->Table("output")) ParseOutputTable(*o, m.length, &m.load_cases[0], &sources);

    if (auto mesh = t->Table("mesh")) {
      Note(sources, "elements_per_section", *mesh, "elements_per_section");
      Note(sources, "elements_across_width", *mesh, "elements_across_width");
      m.elements_per_section = mesh->IntegerIn(
          "elements_per_section", m.elements_per_section, 1, plate::kMaxElementsPerSection);
      // Unset keys stay unset: the theory's own defaults (SensorOptions::ElementOrder(),
      // ElementsAcrossWidth()).
      if (mesh->Has("elements_across_width")) {
        m.elements_across_width =
            mesh->IntegerIn("elements_across_width", 0, 1, plate::kMaxElementsAcrossWidth);
      }
      // The range here; kirchhoff with 2 is refused by SensorOptions::IsValid below, which names
      // the field.
      Note(sources, "element_order", *mesh, "element_order");
      if (mesh->Has("element_order")) m.element_order = mesh->IntegerIn("element_order", 0, 1, 2);
      mesh->Finish();
    }
    t->Finish();
  }

  ValidationError error;
  if (!m.IsValid(&error)) ThrowModelError(error, sources, t ? t->line() : 1, config->path);
}

}  // namespace combabc::config_internal
