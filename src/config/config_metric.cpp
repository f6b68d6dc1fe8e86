// [metric]: the distance's components (paper Eqs. 4-7) and their threshold schedules (Eq. 1).
#include <array>
#include <cmath>
#include <limits>
#include <string>

#include "combabc/config/config.hpp"
#include "combabc/core/error.hpp"
#include "config_reader.hpp"

namespace combabc::config_internal {
namespace {

struct ScheduleSpec {
  ThresholdSchedule schedule;
  Source source;  // where it was written (empty key = defaults)
};

constexpr std::array<const char*, 7> kScheduleKeys = {
    "threshold", "quantile", "acceptance_rate", "ess_fraction", "weighted", "initial", "target"};

bool HasScheduleKeys(const TableReader& t) {
  for (const char* key : kScheduleKeys) {
    if (t.Has(key)) return true;
  }
  return false;
}

ScheduleSpec ParseSchedule(TableReader& t, const ScheduleSpec& fallback) {
  // Every key is read (not just the ones present) so that the table's vocabulary is complete.
  const auto list = t.Numbers("threshold");
  const auto quantile = t.Number("quantile");
  const auto weighted = t.Bool("weighted");
  const auto rate = t.Number("acceptance_rate");
  const auto ess = t.Number("ess_fraction");
  const auto initial = t.Number("initial");
  const auto target = t.Number("target");
  const bool adaptive_keys = quantile || weighted || rate || ess || initial || target;
  if (list && adaptive_keys) {
    t.Fail("threshold",
           "give either threshold = [...] or the adaptive keys (quantile, acceptance_rate, "
           "ess_fraction, initial, target), not both");
  }
  ScheduleSpec spec;
  if (list) {
    spec.schedule.kind = ThresholdKind::kList;
    spec.schedule.values = *list;
    spec.source = {t.Key("threshold"), t.Line("threshold")};
    return spec;
  }
  if (!adaptive_keys) return fallback;
  // One rule: quantile (the default), acceptance_rate or ess_fraction.
  if ((quantile ? 1 : 0) + (rate ? 1 : 0) + (ess ? 1 : 0) > 1) {
    t.Fail(rate ? "acceptance_rate" : "ess_fraction",
           "give one of quantile, acceptance_rate and ess_fraction: each is a rule for eps_t");
  }
  spec.schedule.kind = rate  ? ThresholdKind::kAcceptance
                       : ess ? ThresholdKind::kEss
                             : ThresholdKind::kQuantile;
  const char* first = quantile   ? "quantile"
                      : rate     ? "acceptance_rate"
                      : ess      ? "ess_fraction"
                      : weighted ? "weighted"
                      : initial  ? "initial"
                                 : "target";
  spec.source = {t.Key(first), t.Line(first)};
  if (quantile) {
    if (!(*quantile > 0.0 && *quantile <= 1.0)) t.Fail("quantile", "must be in (0, 1]");
    spec.schedule.quantile = *quantile;
  }
  if (weighted) {
    if (spec.schedule.kind != ThresholdKind::kQuantile) {
      t.Fail("weighted", "only used by the quantile schedule");
    }
    spec.schedule.weighted = *weighted;
  }
  if (rate) {
    if (!(*rate > 0.0 && *rate <= 1.0)) t.Fail("acceptance_rate", "must be in (0, 1]");
    spec.schedule.acceptance_rate = *rate;
  }
  if (ess) {
    if (!(*ess > 0.0 && *ess < 1.0)) t.Fail("ess_fraction", "must be in (0, 1)");
    spec.schedule.ess_fraction = *ess;
  }
  if (initial) {
    if (!(*initial >= 0.0)) t.Fail("initial", "must be >= 0 (inf = accept everything)");
    spec.schedule.initial = *initial;
  }
  if (target) {
    if (!(*target >= 0.0) || !std::isfinite(*target)) t.Fail("target", "must be finite and >= 0");
    spec.schedule.target = *target;
  }
  return spec;
}

struct NoiseSpec {
  NoiseConfig noise;
  bool given = false;  // some noise key was written in this table
};

// noise = "none" | "gaussian" | "folded_normal", sigma_noise = <number> | "estimate",
// sigma_model = <number>.
NoiseSpec ParseNoise(TableReader& t, const NoiseSpec& fallback) {
  const auto model = t.Choice<NoiseModel>("noise", "noise model");
  const toml::node* sigma_node = t.Raw("sigma_noise");
  const auto sigma_model = t.Number("sigma_model");
  NoiseSpec spec = fallback;
  spec.given = false;
  if (!model && !sigma_node && !sigma_model) return spec;
  spec.given = true;
  if (model) spec.noise.model = *model;
  if (spec.noise.model == NoiseModel::kNone) {
    const char* key = sigma_node ? "sigma_noise" : sigma_model ? "sigma_model" : "noise";
    if (key != std::string("noise")) {
      t.Fail(key, "needs a noise model: noise = \"gaussian\" or \"folded_normal\"");
    }
    return spec;
  }
  if (sigma_node) {
    if (const auto* text = sigma_node->as_string()) {
      if (text->get() != "estimate") {
        t.Fail("sigma_noise", "must be a number > 0 or \"estimate\", not " + Excerpt(text->get()));
      }
      spec.noise.sigma_noise.reset();
    } else if (const auto value = sigma_node->value<double>()) {
      if (!(*value > 0.0) || !std::isfinite(*value)) {
        t.Fail("sigma_noise", "must be finite and > 0 (or \"estimate\")");
      }
      spec.noise.sigma_noise = *value;
    } else {
      t.Fail("sigma_noise", "must be a number > 0 or \"estimate\"");
    }
  }
  if (sigma_model) {
    if (!(*sigma_model >= 0.0) || !std::isfinite(*sigma_model)) {
      t.Fail("sigma_model", "must be finite and >= 0");
    }
    spec.noise.sigma_model = *sigma_model;
  }
  return spec;
}

// A noise-aware component's schedule holds temperatures, which end at 1 (the likelihood itself):
// the default target 0 becomes 1; an explicit value below 1 is an error.
void TemperatureSchedule(ScheduleSpec* spec, const TableReader& t, bool target_written) {
  auto& s = spec->schedule;
  if (s.kind == ThresholdKind::kList) {
    for (double v : s.values) {
      if (!(v >= 1.0)) {
        t.Fail("threshold",
               "with a noise model the schedule holds temperatures, which must be >= 1");
      }
    }
    return;
  }
  if (s.target < 1.0) {
    if (target_written) {
      t.Fail("target",
             "with a noise model the schedule holds temperatures: target must be >= 1 "
             "(1 = the posterior under the noise model)");
    }
    s.target = 1.0;
  }
}

void ValidateSchedule(const ScheduleSpec& spec,
                      int num_waves,
                      const std::string& path,
                      const std::string& fallback_key,
                      int fallback_line) {
  ValidationError error;
  if (spec.schedule.IsValid(num_waves, &error)) return;
  const bool known = !spec.source.key.empty();
  throw Error(ErrorKind::kConfig,
              error.Detail(),
              path,
              known ? spec.source.line : fallback_line,
              known ? spec.source.key : fallback_key);
}

}  // namespace

void ParseMetricTable(TableReader& table,
                      LengthUnit position_unit,
                      int num_waves,
                      MetricConfig* metric) {
  TableReader* t = &table;
  const std::string& path = table.path();
  const ScheduleSpec base = ParseSchedule(*t, ScheduleSpec{});
  const NoiseSpec base_noise = ParseNoise(*t, NoiseSpec{});
  bool noise_used = false;
  const auto preset_text = t->String("preset");
  auto components = t->Tables("component");
  if (preset_text && !components.empty()) {
    t->Fail("preset", "give either preset or [[" + t->prefix() + ".component]] tables, not both");
  }
  if (!preset_text && components.empty()) {
    throw Error(ErrorKind::kConfig,
                "give preset = \"area\" | \"least_squares\" | \"split_least_squares\" or one or "
                "more [[" +
                    t->prefix() + ".component]] tables",
                path,
                t->line(),
                t->prefix());
  }
  if (preset_text) {
    const auto preset = ParseEnum<MetricPreset>(*preset_text);
    if (!preset) {
      t->Fail("preset",
              "unknown preset " + Excerpt(*preset_text) + "; expected one of " +
                  EnumChoices<MetricPreset>());
    }
    metric->preset = *preset;
    metric->components = PresetComponents(*preset);
    for (auto& component : metric->components) {
      component.config_line = t->Line("preset");
      if (KindOf(component.type) != ComponentKind::kThreshold) continue;
      ScheduleSpec spec = base;
      if (component.type == MetricType::kLeastSquares) {
        component.noise = base_noise.noise;
        if (base_noise.noise.model != NoiseModel::kNone) {
          noise_used = true;
          TemperatureSchedule(&spec, *t, t->Has("target"));
        }
      }
      ValidateSchedule(spec, num_waves, path, t->Key("preset"), t->Line("preset"));
      component.threshold = spec.schedule;
    }
  }
  const double unit = MetresPer(position_unit);
  for (TableReader& ct : components) {
    MetricComponentConfig component;
    component.config_line = ct.line();
    const auto type = ct.Choice<MetricType>("type", "component type");
    if (!type) ct.Fail("type", "missing required key");
    component.type = *type;
    if (!ct.Has("window")) ct.Fail("window", "missing required key [from, to]");
    std::tie(component.from, component.to) = WindowKey(ct, "window", unit);
    component.name = ct.String("name").value_or("");
    if (KindOf(component.type) == ComponentKind::kIndicator) {
      if (HasScheduleKeys(ct)) {
        const char* key = "target";
        for (const char* k : kScheduleKeys) {
          if (ct.Has(k)) {
            key = k;
            break;
          }
        }
        ct.Fail(key,
                std::string("a ") + ToString(component.type) +
                    " indicator must equal 1 and takes no threshold");
      }
    } else {
      ScheduleSpec spec = ParseSchedule(ct, base);
      const NoiseSpec noise = ParseNoise(ct, base_noise);
      if (component.type == MetricType::kLeastSquares) {
        component.noise = noise.noise;
      } else if (noise.given && noise.noise.model != NoiseModel::kNone) {
        ct.Fail("noise", "a noise model applies to least_squares components only");
      }
      if (component.noise.model != NoiseModel::kNone) {
        noise_used = true;
        const bool own = ct.Has("target") || ct.Has("threshold");
        TemperatureSchedule(&spec, own ? ct : *t, own ? ct.Has("target") : t->Has("target"));
      }
      ValidateSchedule(spec, num_waves, path, ct.prefix(), ct.line());
      component.threshold = spec.schedule;
    }
    ct.Finish();
    metric->components.push_back(std::move(component));
  }
  if (base_noise.given && base_noise.noise.model != NoiseModel::kNone && !noise_used) {
    t->Fail("noise", "no least_squares component to apply it to");
  }
  t->Finish();
}

}  // namespace combabc::config_internal
