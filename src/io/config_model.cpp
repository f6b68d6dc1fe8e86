// [model]: the sensor simulator's options (combabc::plate::SensorOptions), in SI units.
#include <cmath>
#include <limits>
#include <map>

#include "combabc/core/error.hpp"
#include "combabc/io/config.hpp"
#include "config_reader.hpp"

namespace combabc::config_internal {
namespace {

constexpr double kHuge = std::numeric_limits<double>::max();

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

plate::Support SupportKey(TableReader& t, std::string_view key, plate::Support fallback) {
  auto parse = [](const std::string& text) -> std::optional<plate::Support> {
    plate::Support support{};
    if (!plate::FromString(text, &support)) return std::nullopt;
    return support;
  };
  return t.Choice<plate::Support>(key, parse, "support", {"free", "simply_supported", "clamped"})
      .value_or(fallback);
}

plate::Layer ParseLayer(TableReader& t) {
  plate::Layer layer;
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

int ParseModelSection(TableReader& root, CalibrationConfig* config) {
  plate::SensorOptions& m = config->model;
  std::map<std::string, Source> sources;  // SensorOptions field -> config key
  auto t = root.Table("model");
  if (t) {
    sources[""] = {t->prefix(), t->line()};
    Positive(*t, "length", &m.length, &sources, "length");
    Positive(*t, "width", &m.width, &sources, "width");
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
      for (TableReader& lt : layers) m.layers.push_back(ParseLayer(lt));
      sources["layers"] = {t->Key("layer"), t->Line("layer")};
    }

    if (auto c = t->Table("clamps")) {
      const bool per_edge_given = c->Has("per_edge");
      m.clamps_per_edge = c->IntegerIn("per_edge", m.clamps_per_edge, 1, 10000);
      if (const auto section = c->Number("section_length")) {
        // An alternative way to state the layout; it must tile the length exactly.
        if (!(*section > 0.0)) c->Fail("section_length", "must be > 0");
        const double sections = m.length / *section;
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
      }
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
      if (l->Has("x")) sources["load_x"] = {l->Key("x"), l->Line("x")};
      m.load_x = l->NumberIn("x", m.load_x, 0.0, kHuge);
      InRange(*l, "y_fraction", 0.0, 1.0, &m.load_y_fraction, &sources, "load_y_fraction");
      if (const auto force = l->Number("amplitude")) {
        if (!std::isfinite(*force)) l->Fail("amplitude", "must be finite");
        m.load_force = *force;
      }
      InRange(*l, "frequency", 0.0, kHuge, &m.frequency_hz, &sources, "frequency_hz");
      const auto type = l->String("type");
      if (type && *type != "point" && *type != "patch") {
        l->Fail("type",
                "unknown load type " + Excerpt(*type) + "; expected \"point\" or \"patch\"");
      }
      InRange(*l, "patch_length", 0.0, kHuge, &m.load_patch_length, &sources, "load_patch_length");
      InRange(*l, "patch_width", 0.0, kHuge, &m.load_patch_width, &sources, "load_patch_width");
      if (type && *type == "point") {
        if (l->Has("patch_length") || l->Has("patch_width")) {
          l->Fail("type", "a point load takes no patch_length / patch_width");
        }
        m.load_patch_length = 0.0;
        m.load_patch_width = 0.0;
      } else if (type && (m.load_patch_length <= 0.0 || m.load_patch_width <= 0.0)) {
        l->Fail("type", "a patch load needs patch_length and patch_width > 0");
      }
      l->Finish();
    }

    if (auto o = t->Table("output")) {
      if (o->Has("positions") && o->Has("spacing")) {
        o->Fail("spacing", "give either positions or spacing, not both");
      }
      if (const auto positions = o->Numbers("positions")) {
        if (positions->empty()) o->Fail("positions", "must not be empty");
        for (std::size_t k = 1; k < positions->size(); ++k) {
          if (!((*positions)[k] > (*positions)[k - 1])) {
            o->Fail("positions", "must be strictly increasing (entry " + std::to_string(k) + ")");
          }
        }
        m.output_positions = *positions;
        sources["output_positions"] = {o->Key("positions"), o->Line("positions")};
      }
      if (const auto spacing = o->Number("spacing")) {
        if (!(*spacing > 0.0) || *spacing > m.length) {
          o->Fail("spacing", "must be in (0, model.length]");
        }
        // 0, h, 2h, ... up to the length (inclusive within rounding).
        const auto n = static_cast<int>(std::floor(m.length / *spacing + 1e-9));
        m.output_positions.clear();
        for (int k = 0; k <= n; ++k) m.output_positions.push_back(k * *spacing);
        sources["output_positions"] = {o->Key("spacing"), o->Line("spacing")};
      }
      InRange(*o, "y_fraction", 0.0, 1.0, &m.output_y_fraction, &sources, "output_y_fraction");
      o->Finish();
    }

    if (auto mesh = t->Table("mesh")) {
      m.elements_per_section =
          mesh->IntegerIn("elements_per_section", m.elements_per_section, 1, 10000);
      m.elements_across_width =
          mesh->IntegerIn("elements_across_width", m.elements_across_width, 1, 10000);
      mesh->Finish();
    }
    t->Finish();
  }

  std::string why;
  if (!m.IsValid(&why)) {
    // "SensorOptions::field = value; constraint": report at the key that set the field.
    const std::string prefix = "SensorOptions::";
    std::string field = why.rfind(prefix, 0) == 0 ? why.substr(prefix.size()) : why;
    field = field.substr(0, field.find_first_of(" .["));
    auto it = sources.find(field);
    if (it == sources.end()) it = sources.find("");
    const Source source = it != sources.end() ? it->second : Source{"model", 1};
    throw Error(ErrorKind::kConfig, why, config->path, source.line, source.key);
  }
  return 2 * m.clamps_per_edge;
}

}  // namespace combabc::config_internal
