// The answer of a history in numbers (docs/history.md, "The answer").
#include "combabc/export/answer.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <optional>

#include "combabc/export/export.hpp"
#include "combabc/samplers/monte_carlo_error.hpp"
#include "export/json_text.hpp"

namespace combabc {
namespace {

using export_text::JsonArray;
using export_text::JsonNumber;
using export_text::JsonString;

// Centimetres to 0.01 cm, without trailing zeros: 0.15000000000000002 m -> "15".
std::string Centimetres(double metres) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2f", metres * 100.0);
  std::string s = text;
  while (!s.empty() && s.back() == '0') s.pop_back();
  if (!s.empty() && s.back() == '.') s.pop_back();
  return s == "-0" ? "0" : s;
}

// `value` with `digits` decimals, and "±" its standard error when it has one: "0.44±0.02".
std::string Estimate(double value, std::optional<double> se, int digits) {
  char text[64];
  if (se) {
    std::snprintf(text, sizeof text, "%.*f±%.*f", digits, value, digits, *se);
  } else {
    std::snprintf(text, sizeof text, "%.*f", digits, value);
  }
  return text;
}

// The per-wave effort: the weights' ESS and the per-quantity ones (none for an enumeration: its
// numbers are exact).
WaveEffort EffortOf(const WaveRecord& w, bool exact) {
  WaveEffort e{w.wave + 1, w.ess, std::nullopt, {}, w.candidates, w.complete};
  if (w.particles.empty() || exact) return e;
  const WaveErrors errors = WaveMonteCarloErrors(w);
  e.bits_ess = errors.bits_ess;
  for (const WeightedMoment& r : errors.real_means) e.reals_ess.push_back(r.ess);
  return e;
}

// The wave the answer is taken from: the last complete one, else the last with particles.
const WaveRecord* AnswerWave(const RunHistory& h) {
  for (auto it = h.waves.rbegin(); it != h.waves.rend(); ++it) {
    if (it->complete && !it->particles.empty()) return &*it;
  }
  for (auto it = h.waves.rbegin(); it != h.waves.rend(); ++it) {
    if (!it->particles.empty()) return &*it;
  }
  return nullptr;
}

// The most probable configurations, in O(n log n) for n particles: the particles are grouped by
// their bit pattern (a map), and each group's standard error follows from its sums of weights
// and squared weights alone (below), so that no configuration walks every particle (which made
// the answer of a wave of 145,000 distinct particles take minutes).
std::vector<AnswerConfiguration> TopConfigurations(const WaveRecord& w,
                                                   const RunMetadata& metadata,
                                                   bool exact) {
  struct Group {
    double sum = 0.0;      // of the weights
    double squares = 0.0;  // of the squared weights
  };
  std::map<std::string, Group> groups;
  double total = 0.0;
  double total_squares = 0.0;
  std::vector<double> weights;
  weights.reserve(w.particles.size());
  std::string bits;
  for (const Particle& p : w.particles) {
    weights.push_back(p.weight);
    bits.clear();
    for (std::uint8_t b : p.theta.bits) bits += b ? '1' : '0';
    Group& g = groups[bits];
    g.sum += p.weight;
    g.squares += p.weight * p.weight;
    total += p.weight;
    total_squares += p.weight * p.weight;
  }
  std::vector<std::pair<const std::string*, const Group*>> order;
  order.reserve(groups.size());
  for (const auto& [pattern, g] : groups) order.emplace_back(&pattern, &g);
  // Most probable first; equal masses in bit-string order (the map's), so the list never depends
  // on the particles' order.
  const auto mass = [&](const Group& g) { return total > 0 ? g.sum / total : 0.0; };
  std::stable_sort(order.begin(), order.end(), [&](const auto& a, const auto& b) {
    return mass(*a.second) > mass(*b.second);
  });
  if (order.size() > kAnswerConfigurations) order.resize(kAnswerConfigurations);
  const double ess = ProbabilityEss(weights, w.multi_fidelity.has_value());
  std::vector<AnswerConfiguration> top;
  for (const auto& [pattern, g] : order) {
    AnswerConfiguration c;
    c.bits = *pattern;
    c.mass = mass(*g);
    if (!exact) {
      // The mass is the weighted mean mu of the indicator "the particle is this configuration";
      // its delta-method se (WeightedMean) is sqrt(sum_i w_i^2 (1_i - mu)^2) / sum_i w_i, where
      // the sum splits into the group's (1 - mu)^2 S_g and the others' mu^2 (S - S_g), with S
      // the sums of squared weights. A probability, which signed weights can put outside [0, 1]
      // (1.06): clamped, its error covering the raw estimate, and floored by the rule of three
      // (BoundProbability, as WeightedProbability).
      WeightedMoment m;
      m.value = c.mass;
      if (total > 0.0) {
        const double mu = c.mass;
        const double spread = (1.0 - mu) * (1.0 - mu) * g->squares +
                              mu * mu * std::max(total_squares - g->squares, 0.0);
        m.se = std::sqrt(spread) / total;
      } else {
        m.se = std::numeric_limits<double>::infinity();
      }
      m = BoundProbability(m, ess);
      c.mass = m.value;
      c.mass_se = m.se;
    }
    for (std::size_t b = 0; b < c.bits.size(); ++b) {
      if (c.bits[b] == '1') c.fixed.push_back(BitName(metadata, b));
    }
    top.push_back(std::move(c));
  }
  return top;
}

}  // namespace

double AnswerQuantile(const std::vector<double>& values,
                      const std::vector<double>& weights,
                      double alpha) {
  std::vector<std::size_t> order;
  order.reserve(values.size());
  double total = 0.0;
  for (std::size_t i = 0; i < values.size() && i < weights.size(); ++i) {
    order.push_back(i);
    total += std::max(weights[i], 0.0);
  }
  if (!(total > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  // Ties by position, so that the quantile never depends on the sort.
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return values[a] < values[b] || (values[a] == values[b] && a < b);
  });
  double cumulative = 0.0;
  for (std::size_t i : order) {
    cumulative += std::max(weights[i], 0.0);
    if (cumulative >= alpha * total) return values[i];
  }
  return values[order.back()];  // alpha * total a rounding error above the sum
}

Verdict VerdictOf(double p_one, double level) {
  if (p_one >= level) return Verdict::kFixed;
  if (p_one <= 1.0 - level) return Verdict::kFree;
  return Verdict::kNotDetermined;
}

std::string BitPosition::Text() const {
  return "edge " + std::to_string(edge) + ", " + Centimetres(start_m) + "-" + Centimetres(end_m) +
         " cm";
}

namespace {

// Real r's 5 %, 50 % and 95 % quantiles among the wave's particles, under their stored weights
// (the estimator's, as the means).
void RealQuantiles(const WaveRecord& w, std::size_t r, AnswerReal& real) {
  std::vector<double> values;
  std::vector<double> weights;
  values.reserve(w.particles.size());
  weights.reserve(w.particles.size());
  for (const Particle& p : w.particles) {
    if (r >= p.theta.reals.size()) continue;
    values.push_back(p.theta.reals[r]);
    weights.push_back(p.weight);
  }
  real.q05 = AnswerQuantile(values, weights, 0.05);
  real.median = AnswerQuantile(values, weights, 0.5);
  real.q95 = AnswerQuantile(values, weights, 0.95);
}

}  // namespace

Answer SummariseAnswer(const RunMetadata& m,
                       const RunHistory& h,
                       const std::vector<std::optional<BitPosition>>& positions) {
  Answer a;
  a.termination = m.termination;
  a.exact = m.termination == ToString(Termination::kEnumerated);
  const Estimator estimator = ParseEnum<Estimator>(m.estimator).value_or(Estimator::kPaper);
  a.estimator = ToString(estimator);
  a.waves = static_cast<int>(h.waves.size());
  for (const WaveRecord& w : h.waves) {
    a.per_wave.push_back(EffortOf(w, a.exact));
    a.simulations += w.candidates;
    if (w.multi_fidelity) {
      a.expensive_simulations =
          a.expensive_simulations.value_or(0) + w.multi_fidelity->expensive_simulations;
    }
    for (const PatternClass& c : w.pattern_classes) {
      if (c.flagged) a.mode_loss.push_back({w.wave + 1, PatternText(c.bits), c.mass, c.proposal});
    }
    const std::string warning = ModeLossWarning(w);
    if (!warning.empty()) a.mode_loss_warnings.push_back(warning);
  }
  const WaveRecord* w = AnswerWave(h);
  if (w == nullptr) return a;
  a.wave = w->wave + 1;
  a.complete = w->complete;
  // The wave's thresholds hold one slot per non-indicator component, a likelihood's temperature.
  std::size_t slot = 0;
  for (const DistanceComponent& c : m.distance_components) {
    if (c.kind == ComponentKind::kIndicator) continue;
    if (c.kind == ComponentKind::kNegLogLikelihood && slot < w->thresholds.size()) {
      a.temperatures.push_back({c.name, w->thresholds[slot]});
      // NaN is no temperature of 1 either.
      a.tempered = a.tempered || !(w->thresholds[slot] <= 1.0);
    }
    ++slot;
  }
  // An enumeration's wave counts every accepted configuration, also those it did not keep.
  a.particles = std::max(w->accepted, static_cast<std::int64_t>(w->particles.size()));
  a.distinct = w->distinct;
  // The particles' stored weights are the estimator's (the paper estimator's equal ones, the
  // importance estimator's p/q): one delta-method formula serves both, and signed weights.
  const WaveErrors errors = WaveMonteCarloErrors(*w, m.bit_prior_one);
  const std::vector<double>& p = w->marginals(estimator);
  for (std::size_t b = 0; b < p.size(); ++b) {
    AnswerBit bit;
    bit.number = static_cast<int>(b) + 1;
    bit.name = BitName(m, b);
    if (b < positions.size()) bit.position = positions[b];
    // A sum of weights may pass 1 by a rounding error (1.0000000000000007): a probability.
    bit.p_one = std::clamp(p[b], 0.0, 1.0);
    bit.mc_se = a.exact || b >= errors.bits.size() ? 0.0 : errors.bits[b].se;
    bit.verdict = VerdictOf(bit.p_one, a.verdict_level);
    a.bits.push_back(std::move(bit));
  }
  // Without bits every particle is the one empty configuration: nothing to list.
  if (!a.bits.empty()) a.top_configurations = TopConfigurations(*w, m, a.exact);
  for (std::size_t r = 0; r < m.reals.size() && r < w->reals_mean.size(); ++r) {
    AnswerReal real;
    real.name = m.reals[r].name;
    real.mean = w->reals_mean[r];
    real.sd = r < w->reals_sd.size() ? w->reals_sd[r] : 0.0;
    if (r < errors.real_means.size()) {
      real.ess = errors.real_means[r].ess;
      if (!a.exact) {
        real.mc_se = errors.real_means[r].se;
        real.sd_se = errors.real_sds[r].se;
      }
    }
    RealQuantiles(*w, r, real);
    a.reals.push_back(std::move(real));
  }
  return a;
}

std::string AnswerJson(const Answer& a, int indent) {
  const std::string in(static_cast<std::size_t>(indent), ' ');
  const std::string in2 = in + "  ";
  std::string out = "{\n";
  out += in2 + "\"wave\": " + std::to_string(a.wave) + ",\n";
  out += in2 + "\"complete\": " + (a.complete ? "true" : "false") + ",\n";
  out += in2 + "\"estimator\": " + JsonString(a.estimator) + ",\n";
  out += in2 + "\"verdict_level\": " + JsonNumber(a.verdict_level) + ",\n";
  out += in2 + "\"bits\": [";
  for (std::size_t b = 0; b < a.bits.size(); ++b) {
    const AnswerBit& x = a.bits[b];
    const auto& at = x.position;
    out += std::string(b ? "," : "") + "\n" + in2 + "  {\"number\": " + std::to_string(x.number) +
           ", \"name\": " + JsonString(x.name) +
           ", \"position\": " + (at ? JsonString(at->Text()) : "null") +
           ", \"edge\": " + (at ? std::to_string(at->edge) : "null") +
           ", \"start_m\": " + (at ? JsonNumber(at->start_m) : "null") +
           ", \"end_m\": " + (at ? JsonNumber(at->end_m) : "null") +
           ", \"p_one\": " + JsonNumber(x.p_one) + ", \"mc_se\": " + JsonNumber(x.mc_se) +
           ", \"verdict\": " + JsonString(ToString(x.verdict)) + "}";
  }
  out += std::string(a.bits.empty() ? "" : "\n" + in2) + "],\n";
  out += in2 + "\"top_configurations\": [";
  for (std::size_t k = 0; k < a.top_configurations.size(); ++k) {
    const AnswerConfiguration& c = a.top_configurations[k];
    out += std::string(k ? "," : "") + "\n" + in2 + "  {\"bits\": " + JsonString(c.bits) +
           ", \"mass\": " + JsonNumber(c.mass) +
           ", \"mass_se\": " + (c.mass_se ? JsonNumber(*c.mass_se) : "null") + ", \"fixed\": [";
    for (std::size_t i = 0; i < c.fixed.size(); ++i) {
      out += (i ? ", " : "") + JsonString(c.fixed[i]);
    }
    out += "]}";
  }
  out += std::string(a.top_configurations.empty() ? "" : "\n" + in2) + "],\n";
  if (!a.reals.empty()) {
    out += in2 + "\"reals\": [";
    for (std::size_t r = 0; r < a.reals.size(); ++r) {
      const AnswerReal& x = a.reals[r];
      out += std::string(r ? "," : "") + "\n" + in2 + "  {\"name\": " + JsonString(x.name) +
             ", \"mean\": " + JsonNumber(x.mean) + ", \"mc_se\": " + JsonNumber(x.mc_se) +
             ", \"sd\": " + JsonNumber(x.sd) + ", \"sd_se\": " + JsonNumber(x.sd_se) +
             ", \"ess\": " + JsonNumber(x.ess) + ", \"q05\": " + JsonNumber(x.q05) +
             ", \"median\": " + JsonNumber(x.median) + ", \"q95\": " + JsonNumber(x.q95) + "}";
    }
    out += "\n" + in2 + "],\n";
  }
  out += in2 + "\"mode_loss\": [";
  for (std::size_t k = 0; k < a.mode_loss.size(); ++k) {
    const ModeLossFlag& f = a.mode_loss[k];
    out += std::string(k ? "," : "") + "\n" + in2 + "  {\"wave\": " + std::to_string(f.wave) +
           ", \"bits\": " + JsonString(f.bits) + ", \"mass\": " + JsonNumber(f.mass) +
           ", \"proposal\": " + JsonNumber(f.proposal) + "}";
  }
  out += std::string(a.mode_loss.empty() ? "" : "\n" + in2) + "],\n";
  out += in2 + "\"tempered\": " + (a.tempered ? "true" : "false") + ",\n";
  out += in2 + "\"temperatures\": [";
  for (std::size_t k = 0; k < a.temperatures.size(); ++k) {
    out += std::string(k ? ", " : "") +
           "{\"component\": " + JsonString(a.temperatures[k].component) +
           ", \"temperature\": " + JsonNumber(a.temperatures[k].temperature) + "}";
  }
  out += "],\n";
  out += in2 + "\"exact\": " + (a.exact ? "true" : "false") + ",\n";
  out += in2 + "\"particles\": " + std::to_string(a.particles) + ",\n";
  out += in2 + "\"distinct\": " + std::to_string(a.distinct) + ",\n";
  if (a.expensive_simulations) {
    out += in2 + "\"expensive_simulations\": " + std::to_string(*a.expensive_simulations) + ",\n";
  }
  out += in2 + "\"per_wave\": [";
  for (std::size_t t = 0; t < a.per_wave.size(); ++t) {
    const WaveEffort& e = a.per_wave[t];
    out += std::string(t ? "," : "") + "\n" + in2 + "  {\"wave\": " + std::to_string(e.wave) +
           ", \"ess\": " + JsonNumber(e.ess) +
           ", \"ess_bits\": " + (e.bits_ess ? JsonNumber(*e.bits_ess) : "null") +
           ", \"ess_reals\": " + JsonArray(e.reals_ess) +
           ", \"simulations\": " + std::to_string(e.simulations) + "}";
  }
  out += std::string(a.per_wave.empty() ? "" : "\n" + in2) + "]\n" + in + "}";
  return out;
}

namespace {

// `text` padded with spaces to `width` characters (UTF-8: "±" is one).
std::string Pad(const std::string& text, std::size_t width) {
  std::size_t chars = 0;
  for (char c : text) chars += (static_cast<unsigned char>(c) & 0xC0) != 0x80;
  return text + std::string(chars < width ? width - chars : 0, ' ');
}

// "0.44±0.02", or "1.00" when exact.
std::string Probability(const AnswerBit& b, bool exact) {
  return Estimate(b.p_one, exact ? std::nullopt : std::optional<double>(b.mc_se), 2);
}

// The sensor's clamps, one table per edge side by side: every bit has a position on edge 1 or 2.
bool SideBySide(const Answer& a) {
  return !a.bits.empty() && std::all_of(a.bits.begin(), a.bits.end(), [](const AnswerBit& b) {
    return b.position && (b.position->edge == 1 || b.position->edge == 2);
  });
}

void ClampTables(const Answer& a, std::string& out) {
  std::vector<const AnswerBit*> edges[2];
  for (const AnswerBit& b : a.bits) edges[b.position->edge - 1].push_back(&b);
  const std::string header = "clamp    cm  " + Pad("P(fixed)", 9) + "  verdict";
  out += " " + Pad("edge 1 (y = 0)", 40) + "edge 2 (y = width)\n";
  out += " " + Pad(header, 40) + header + "\n";
  const std::size_t rows = std::max(edges[0].size(), edges[1].size());
  for (std::size_t r = 0; r < rows; ++r) {
    std::string line;
    for (const auto& edge : edges) {
      if (r < edge.size()) {
        char cell[32];
        const AnswerBit& b = *edge[r];
        const std::string cm =
            Centimetres(b.position->start_m) + "-" + Centimetres(b.position->end_m);
        std::snprintf(cell, sizeof cell, "%5d %5s  ", b.number, cm.c_str());
        line += " " + std::string(cell) + Pad(Probability(b, a.exact), 9) + "  " +
                Pad(ToString(b.verdict), 14) + " ";
      } else {
        line += std::string(40, ' ');
      }
    }
    while (!line.empty() && line.back() == ' ') line.pop_back();
    out += line + "\n";
  }
}

void BitLines(const Answer& a, std::string& out) {
  // Thousands of bits do not fit a screen: the first ones, and where the rest are.
  constexpr std::size_t kMaxLines = 60;
  std::size_t width = 4;
  for (const AnswerBit& b : a.bits) {
    width = std::max(width, std::min<std::size_t>(b.name.size(), 24));
  }
  out += " " + Pad("bit", width) + "  P(bit = 1)  verdict\n";
  for (std::size_t k = 0; k < a.bits.size() && k < kMaxLines; ++k) {
    const AnswerBit& b = a.bits[k];
    std::string line = " " + Pad(b.name, width) + "  " + Pad(Probability(b, a.exact), 10) + "  " +
                       ToString(b.verdict);
    if (b.position) line += "  (" + b.position->Text() + ")";
    out += line + "\n";
  }
  if (a.bits.size() > kMaxLines) {
    out += " ... " + std::to_string(a.bits.size() - kMaxLines) +
           " more bits in summary.json's \"answer\" (combabc export)\n";
  }
}

// A configuration's bits, the sensor's edges apart.
std::string Bits(const Answer& a, const std::string& bits, bool side_by_side) {
  constexpr std::size_t kMaxBits = 72;
  if (bits.size() > kMaxBits) return bits.substr(0, kMaxBits) + "...";
  if (!side_by_side) return bits;
  std::string out;
  for (std::size_t b = 0; b < bits.size(); ++b) {
    if (b > 0 && a.bits[b].position->edge != a.bits[b - 1].position->edge) out += ' ';
    out += bits[b];
  }
  return out;
}

// Per wave: the weights' ESS, the bits' (the smallest per-bit one) and each real's, and the
// simulations; eight waves a row.
void EffortTable(const Answer& a, std::string& out) {
  constexpr std::size_t kPerRow = 8;
  // An enumeration is exact: no per-quantity ESS to show.
  const bool bits = !a.bits.empty() && !a.exact;
  std::vector<std::string> labels = {"wave", "ESS"};
  if (bits) labels.push_back("ESS bits");
  for (const AnswerReal& r : a.reals) labels.push_back("ESS " + r.name);
  labels.push_back("simulations");
  std::size_t width = 0;
  for (const std::string& l : labels) width = std::max(width, l.size());
  bool incomplete = false;
  for (std::size_t first = 0; first < a.per_wave.size(); first += kPerRow) {
    std::vector<std::string> rows;
    rows.reserve(labels.size());
    for (const std::string& l : labels) rows.push_back(" " + Pad(l, width));
    for (std::size_t t = first; t < a.per_wave.size() && t < first + kPerRow; ++t) {
      const WaveEffort& e = a.per_wave[t];
      char cell[32];
      std::size_t row = 0;
      std::snprintf(cell, sizeof cell, "%8d%s", e.wave, e.complete ? " " : "*");
      rows[row++] += cell;
      std::snprintf(cell, sizeof cell, "%8.0f ", e.ess);
      rows[row++] += cell;
      // "-": a wave without particles, or (the bits) none of whose bits varies.
      if (bits) {
        if (e.bits_ess) {
          std::snprintf(cell, sizeof cell, "%8.0f ", *e.bits_ess);
        } else {
          std::snprintf(cell, sizeof cell, "%8s ", "-");
        }
        rows[row++] += cell;
      }
      for (std::size_t r = 0; r < a.reals.size(); ++r) {
        if (r < e.reals_ess.size()) {
          std::snprintf(cell, sizeof cell, "%8.0f ", e.reals_ess[r]);
        } else {
          std::snprintf(cell, sizeof cell, "%8s ", "-");
        }
        rows[row++] += cell;
      }
      std::snprintf(cell, sizeof cell, "%8lld ", static_cast<long long>(e.simulations));
      rows[row++] += cell;
      incomplete = incomplete || !e.complete;
    }
    for (std::string& row : rows) {
      while (!row.empty() && row.back() == ' ') row.pop_back();
      out += row + "\n";
    }
  }
  if (incomplete) out += " * incomplete wave (fewer particles than accepted_per_wave)\n";
}

// The bits: P(bit = 1) with verdicts, then the `configurations` most probable configurations.
void BitsText(const Answer& a, std::size_t configurations, std::string& out) {
  const bool sensor = SideBySide(a);
  char line[256];
  const std::string what = sensor ? "P(fixed)" : "P(bit = 1)";
  if (a.exact) {
    out += " " + what + " exact (no Monte-Carlo error)\n";
  } else {
    // The bits' ESS: the smallest per-bit one (each bit's own, Var_w / SE^2).
    const WaveEffort& e = a.per_wave[static_cast<std::size_t>(a.wave - 1)];
    std::snprintf(line,
                  sizeof line,
                  " %s ± its Monte-Carlo standard error (delta method; ESS of the bits >= %.0f)\n",
                  what.c_str(),
                  e.bits_ess.value_or(e.ess));
    out += line;
  }
  std::snprintf(line,
                sizeof line,
                " verdict: fixed if P >= %.2f, free if P <= %.2f, else not determined\n",
                a.verdict_level,
                1.0 - a.verdict_level);
  out += line;
  if (sensor) {
    ClampTables(a, out);
  } else {
    BitLines(a, out);
  }
  // Every particle a configuration of its own: their equal masses single none out, and listing
  // them would read as if they did.
  const bool all_distinct = !a.exact && a.particles > 1 && a.distinct == a.particles;
  const std::size_t shown =
      all_distinct ? 0 : std::min(configurations, a.top_configurations.size());
  if (all_distinct) {
    out += "most probable configurations: none stands out (" + std::to_string(a.particles) +
           " particles, all distinct)\n";
  } else if (shown > 0) {
    out += "most probable configurations (" + std::string(sensor ? "1 = fixed" : "bit 1 first") +
           "), posterior mass" + (a.exact ? " (exact)" : " ± standard error") + ":\n";
  }
  for (std::size_t k = 0; k < shown; ++k) {
    const AnswerConfiguration& c = a.top_configurations[k];
    const std::string mass = Estimate(c.mass, c.mass_se, 3);
    out +=
        " " + std::to_string(k + 1) + ". " + Pad(mass, 11) + "  " + Bits(a, c.bits, sensor) + "\n";
  }
}

// The continuous parameters: posterior mean and sd, each ± its Monte-Carlo standard error, and
// the mean's ESS.
void RealLines(const Answer& a, std::string& out) {
  if (a.reals.empty()) return;
  std::size_t width = 9;  // "parameter"
  for (const AnswerReal& r : a.reals) width = std::max(width, r.name.size());
  out += " " + Pad("parameter", width) + "  posterior mean" + (a.exact ? "" : " ± standard error") +
         ", sd" + (a.exact ? "" : " ± standard error (delta method), ESS") + "\n";
  for (const AnswerReal& r : a.reals) {
    char text[160];
    if (a.exact) {
      std::snprintf(text, sizeof text, "%.6g, sd %.4g", r.mean, r.sd);
    } else {
      std::snprintf(text,
                    sizeof text,
                    "%.6g ± %.2g, sd %.4g ± %.2g, ESS %.0f",
                    r.mean,
                    r.mc_se,
                    r.sd,
                    r.sd_se,
                    r.ess);
    }
    out += " " + Pad(r.name, width) + "  " + text + "\n";
  }
}

// " tempered: ..." with each likelihood component's temperature: the numbers are not the
// posterior the docs promise, and nothing else on the screen would say so.
std::string TemperedLine(const Answer& a) {
  std::string temperatures;
  for (const AnswerTemperature& t : a.temperatures) {
    char value[32];
    std::snprintf(value, sizeof value, "%.3g", t.temperature);
    temperatures +=
        (temperatures.empty() ? "" : ", ") + std::string(value) + " (" + t.component + ")";
  }
  return " tempered: the likelihood's temperatures are " + temperatures +
         ": only T = 1 is the posterior under the noise model, these numbers are a flatter, "
         "tempered one (a run stopped by a limit goes on towards T = 1 when resumed past it; "
         "[metric] target = 1)\n";
}

}  // namespace

std::string AnswerText(const Answer& a, std::size_t configurations) {
  std::string out;
  if (a.wave == 0) {
    return "answer: none yet (no wave accepted a particle)\n";
  }
  char line[256];
  if (a.exact) {
    out += "answer: exact (enumeration, " + std::to_string(a.particles) +
           " accepted configuration" + (a.particles == 1 ? "" : "s") + ")\n";
  } else {
    std::snprintf(line,
                  sizeof line,
                  "answer: wave %d of %d, %s estimator, %lld particles",
                  a.wave,
                  a.waves,
                  a.estimator.c_str(),
                  static_cast<long long>(a.particles));
    out += line;
    // Distinct configurations of bits: a continuous-only run has one, the empty one.
    out += a.bits.empty() ? "\n" : " (" + std::to_string(a.distinct) + " distinct)\n";
  }
  if (!a.complete) {
    out += " no complete wave: the numbers are those of the incomplete last wave\n";
  } else if (a.wave < a.waves) {
    std::snprintf(line,
                  sizeof line,
                  " the numbers are wave %d's: wave %d is incomplete (%s)\n",
                  a.wave,
                  a.waves,
                  a.termination.empty() ? "stopped" : a.termination.c_str());
    out += line;
  }
  if (a.tempered) out += TemperedLine(a);
  if (!a.bits.empty()) BitsText(a, configurations, out);
  RealLines(a, out);
  EffortTable(a, out);
  if (a.expensive_simulations) {
    const double share = a.simulations > 0 ? 100.0 * static_cast<double>(*a.expensive_simulations) /
                                                 static_cast<double>(a.simulations)
                                           : 0.0;
    std::snprintf(line,
                  sizeof line,
                  " multi-fidelity: %lld expensive simulations for %lld candidates (%.1f %%), "
                  "each of which ran the cheap simulator\n",
                  static_cast<long long>(*a.expensive_simulations),
                  static_cast<long long>(a.simulations),
                  share);
    out += line;
  }
  for (const std::string& warning : a.mode_loss_warnings) out += "warning: " + warning + "\n";
  return out;
}

}  // namespace combabc
