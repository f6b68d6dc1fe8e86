// Export of a run history to CSV + JSON (files and columns: docs/history.md, "Export").
#include "combabc/export/export.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>

#include "combabc/core/check.hpp"
#include "combabc/core/error.hpp"
#include "combabc/core/output_files.hpp"
#include "combabc/export/answer.hpp"
#include "combabc/export/fit_checks.hpp"
#include "combabc/samplers/monte_carlo_error.hpp"
#include "export/json_text.hpp"

namespace combabc {
namespace {

using export_text::JsonArray;
using export_text::JsonNumber;
using export_text::JsonString;
using export_text::Number;

// Quoted only when needed (RFC 4180), so plain names stay plain for MATLAB.
std::string CsvField(const std::string& text) {
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

// A column-name-safe version of a component name: "least squares" -> "least_squares".
std::string Identifier(const std::string& name) {
  std::string out;
  for (char c : name) {
    const bool word = std::isalnum(static_cast<unsigned char>(c)) != 0;
    if (word) {
      out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    } else if (!out.empty() && out.back() != '_') {
      out += '_';
    }
  }
  while (!out.empty() && out.back() == '_') out.pop_back();
  return out;
}

}  // namespace

std::string BitName(const RunMetadata& m, std::size_t b) {
  return b < m.bit_names.size() ? m.bit_names[b] : "bit " + std::to_string(b + 1);
}

std::vector<std::string> ThresholdColumns(const RunMetadata& m, std::size_t count) {
  std::vector<std::string> names;
  for (std::size_t c = 0; c < m.distance_components.size(); ++c) {
    if (m.distance_components[c].kind != ComponentKind::kIndicator) {
      // A likelihood component's schedule slot holds its temperature.
      const bool likelihood = m.distance_components[c].kind == ComponentKind::kNegLogLikelihood;
      names.push_back((likelihood ? "T_" : "eps_") + Identifier(m.distance_components[c].name));
    }
  }
  if (names.size() != count) {
    names.clear();
    for (std::size_t k = 0; k < count; ++k) names.push_back("eps_" + std::to_string(k));
  }
  return names;
}

std::vector<std::string> DistanceColumns(const RunMetadata& m, std::size_t count) {
  std::vector<std::string> names;
  for (const DistanceComponent& c : m.distance_components) {
    names.push_back("d_" + Identifier(c.name));
  }
  if (names.size() != count) {
    names.clear();
    for (std::size_t k = 0; k < count; ++k) names.push_back("d_" + std::to_string(k));
  }
  return names;
}

std::vector<ExperimentSlice> ExperimentSlices(const RunMetadata& m) {
  std::vector<ExperimentSlice> slices;
  ExperimentSlice next;
  for (const StoredExperiment& x : m.experiments) {
    if (x.outputs < 0 || x.measured < 0 || x.components < 0) break;
    next.name = x.name;
    next.description = x.description;
    next.outputs = static_cast<std::size_t>(x.outputs);
    next.measured = static_cast<std::size_t>(x.measured);
    next.components = static_cast<std::size_t>(x.components);
    slices.push_back(next);
    next.first_output += next.outputs;
    next.first_measured += next.measured;
    next.first_component += next.components;
  }
  const bool adds_up = slices.size() == m.experiments.size() &&
                       next.first_output == m.output_positions.size() &&
                       next.first_measured == m.measured.positions.size() &&
                       next.first_component == m.distance_components.size();
  if (!slices.empty() && adds_up) return slices;
  ExperimentSlice all;
  all.outputs = m.output_positions.size();
  all.measured = m.measured.positions.size();
  all.components = m.distance_components.size();
  return {all};
}

bool HasNamedExperiments(const RunMetadata& m) {
  for (const ExperimentSlice& x : ExperimentSlices(m)) {
    if (!x.name.empty()) return true;
  }
  return false;
}

namespace {

// Each row's experiment name, for the experiment column of positions.csv (outputs) and
// measured.csv (measured points) of a run with named experiments.
std::vector<std::string> ExperimentOfEach(const std::vector<ExperimentSlice>& slices,
                                          std::size_t ExperimentSlice::*count,
                                          std::size_t rows) {
  std::vector<std::string> names;
  for (const ExperimentSlice& x : slices) names.insert(names.end(), x.*count, x.name);
  names.resize(rows);
  return names;
}

// A multi-fidelity run: one of its waves ran a low-fidelity simulator. Only then do the exported
// files have the multi-fidelity columns and summary.json its "multi_fidelity" block.
bool MultiFidelity(const RunHistory& h) {
  return std::any_of(
      h.waves.begin(), h.waves.end(), [](const WaveRecord& w) { return w.multi_fidelity; });
}

// A resample-move run: one of its waves moved particles. Only then do the exported files have the
// move columns (waves.csv), the ancestor (particles.csv) and summary.json's waves their "moves".
bool Moves(const RunHistory& h) {
  return std::any_of(h.waves.begin(), h.waves.end(), [](const WaveRecord& w) { return w.moves; });
}

// The moves' acceptance rate and the share of proposals from the fitted kernel (NaN without
// proposals).
double MoveAcceptance(const WaveMoves& m) {
  return m.proposed > 0 ? static_cast<double>(m.accepted) / static_cast<double>(m.proposed)
                        : std::nan("");
}
double IndependentShare(const WaveMoves& m) {
  return m.proposed > 0
             ? static_cast<double>(m.independent_proposed) / static_cast<double>(m.proposed)
             : std::nan("");
}

// Waves are numbered from 1 in every exported file, as in the paper, the CLI and the report (the
// database keeps the engine's 0-based numbers).
int WaveNumber(const WaveRecord& w) { return w.wave + 1; }

// A wave's Monte-Carlo errors (samplers/monte_carlo_error.hpp); none for an enumeration, whose
// numbers are exact.
WaveErrors ErrorsOf(const RunMetadata& m, const WaveRecord& w) {
  if (m.termination == ToString(Termination::kEnumerated)) return {};
  return WaveMonteCarloErrors(w, m.bit_prior_one);
}

// A wave's "waves" entry's errors (docs/history.md): per bit its standard error and ESS, the
// bits' ESS (null when no bit varies), per real its mean's and sd's standard errors and its
// mean's ESS.
std::string WaveErrorsJson(const WaveErrors& e) {
  std::vector<double> se, ess, mean_se, sd_se, reals_ess;
  for (const WeightedMoment& b : e.bits) {
    se.push_back(b.se);
    ess.push_back(b.ess);
  }
  for (std::size_t r = 0; r < e.real_means.size(); ++r) {
    mean_se.push_back(e.real_means[r].se);
    sd_se.push_back(e.real_sds[r].se);
    reals_ess.push_back(e.real_means[r].ess);
  }
  return ",\n     \"marginals_se\": " + JsonArray(se) + ", \"marginals_ess\": " + JsonArray(ess) +
         ", \"ess_bits\": " + (e.bits_ess ? JsonNumber(*e.bits_ess) : "null") +
         ",\n     \"reals_mean_se\": " + JsonArray(mean_se) +
         ", \"reals_sd_se\": " + JsonArray(sd_se) + ", \"reals_ess\": " + JsonArray(reals_ess);
}

void WriteWaves(OutputDirectory& dir, const RunMetadata& m, const RunHistory& h) {
  std::ostream& out = dir.Add("waves.csv");
  const std::size_t k = h.waves.empty() ? 0 : h.waves.front().thresholds.size();
  out << "wave";
  for (const std::string& name : ThresholdColumns(m, k)) out << ',' << name;
  out << ",phi,candidates,accepted,acceptance_rate,ess,distinct,wall_seconds,complete";
  // The reals' estimates, last: files of runs without reals keep their columns and order.
  for (const ContinuousParameter& r : m.reals) {
    out << ',' << CsvField(r.name + "_mean") << ',' << CsvField(r.name + "_sd");
  }
  // The Monte-Carlo errors (samplers/monte_carlo_error.hpp), after the estimates: the bits' ESS
  // (the smallest per-bit one), then per real its mean's and sd's standard errors and its
  // mean's ESS.
  out << ",ess_bits";
  for (const ContinuousParameter& r : m.reals) {
    out << ',' << CsvField(r.name + "_mean_se") << ',' << CsvField(r.name + "_sd_se") << ','
        << CsvField(r.name + "_ess");
  }
  // A multi-fidelity run's continuation probabilities and costs, after everything else.
  const bool fidelity = MultiFidelity(h);
  if (fidelity) {
    out << ",continue_if_accepted,continue_if_rejected,expensive_simulations,cheap_seconds,"
           "expensive_seconds,next_continue_if_accepted,next_continue_if_rejected,cost_ratio";
  }
  // A resample-move run's move statistics, last (NaN in its waves drawn by rejection).
  const bool moves = Moves(h);
  if (moves) {
    out << ",move_rounds,move_proposed,move_accepted,move_acceptance_rate,"
           "move_independent_proposed,move_independent_accepted,move_independent_share,"
           "move_survivor_ess,move_step";
  }
  out << '\n';
  for (const WaveRecord& w : h.waves) {
    out << WaveNumber(w);
    for (std::size_t i = 0; i < k; ++i) {
      out << ',' << (i < w.thresholds.size() ? Number(w.thresholds[i]) : "NaN");
    }
    out << ',' << Number(w.phi) << ',' << w.candidates << ',' << w.accepted << ','
        << Number(w.acceptance_rate) << ',' << Number(w.ess) << ',' << w.distinct << ','
        << Number(w.wall_seconds) << ',' << (w.complete ? 1 : 0);
    for (std::size_t i = 0; i < m.reals.size(); ++i) {
      // A wave that accepted nothing has no estimates.
      out << ',' << (i < w.reals_mean.size() ? Number(w.reals_mean[i]) : "NaN") << ','
          << (i < w.reals_sd.size() ? Number(w.reals_sd[i]) : "NaN");
    }
    // NaN: an enumeration, no particles, or (ess_bits) no bit that varies among them.
    const WaveErrors e = ErrorsOf(m, w);
    out << ',' << (e.bits_ess ? Number(*e.bits_ess) : "NaN");
    for (std::size_t i = 0; i < m.reals.size(); ++i) {
      if (i < e.real_means.size()) {
        out << ',' << Number(e.real_means[i].se) << ',' << Number(e.real_sds[i].se) << ','
            << Number(e.real_means[i].ess);
      } else {
        out << ",NaN,NaN,NaN";
      }
    }
    if (fidelity) {
      const WaveFidelity f = w.multi_fidelity.value_or(WaveFidelity{});
      out << ',' << Number(f.continue_if_accepted) << ',' << Number(f.continue_if_rejected) << ','
          << f.expensive_simulations << ',' << Number(f.cheap_seconds) << ','
          << Number(f.expensive_seconds) << ',' << Number(f.next_continue_if_accepted) << ','
          << Number(f.next_continue_if_rejected) << ',' << Number(f.cost_ratio);
    }
    if (moves && w.moves) {
      const WaveMoves& v = *w.moves;
      out << ',' << v.rounds << ',' << v.proposed << ',' << v.accepted << ','
          << Number(MoveAcceptance(v)) << ',' << v.independent_proposed << ','
          << v.independent_accepted << ',' << Number(IndependentShare(v)) << ','
          << Number(v.survivor_ess) << ',' << Number(v.step);
    } else if (moves) {
      out << ",NaN,NaN,NaN,NaN,NaN,NaN,NaN,NaN,NaN";
    }
    out << '\n';
  }
}

void WriteMarginals(OutputDirectory& dir, const RunMetadata& m, const RunHistory& h) {
  std::ostream& out = dir.Add("marginals.csv");
  out << "wave,bit,name,prob_paper,prob_importance\n";
  for (const WaveRecord& w : h.waves) {
    for (std::size_t b = 0; b < w.marginals_paper.size(); ++b) {
      const std::string name = BitName(m, b);
      const double importance =
          b < w.marginals_importance.size() ? w.marginals_importance[b] : std::nan("");
      out << WaveNumber(w) << ',' << b + 1 << ',' << CsvField(name) << ','
          << Number(w.marginals_paper[b]) << ',' << Number(importance) << '\n';
    }
  }
}

// Long, one row per wave and pair of bits i < j (the matrix is symmetric, its diagonal 1 or 0).
void WritePairCorrelations(OutputDirectory& dir, const RunMetadata& m, const RunHistory& h) {
  std::ostream& out = dir.Add("pair_correlations.csv");
  out << "wave,bit_i,name_i,bit_j,name_j,correlation\n";
  auto name = [&](std::size_t b) { return CsvField(BitName(m, b)); };
  for (const WaveRecord& w : h.waves) {
    // PairCorrelations(w.particles): none beyond kMaxPairCorrelationBits bits.
    const std::size_t d = w.particles.empty() || w.pair_correlations.empty()
                              ? 0
                              : w.particles.front().theta.bits.size();
    COMBABC_CHECK(w.pair_correlations.size() == d * d);
    for (std::size_t i = 0; i < d; ++i) {
      for (std::size_t j = i + 1; j < d; ++j) {
        out << WaveNumber(w) << ',' << i + 1 << ',' << name(i) << ',' << j + 1 << ',' << name(j)
            << ',' << Number(w.pair_correlations[i * d + j]) << '\n';
      }
    }
  }
}

void WriteParticles(OutputDirectory& dir, const RunMetadata& m, const RunHistory& h) {
  std::ostream& out = dir.Add("particles.csv");
  std::size_t components = m.distance_components.size();
  for (const WaveRecord& w : h.waves) {
    if (!w.particles.empty()) components = w.particles.front().distance.size();
  }
  out << "wave,index,bits";
  // One column per bit, named as summary.json's bit_names (docs/history.md, "Numbering").
  for (std::size_t b = 0; b < static_cast<std::size_t>(m.dimension); ++b) {
    out << ',' << CsvField(BitName(m, b));
  }
  // theta is the bits and then the reals, one column each, named by the parameter.
  for (const ContinuousParameter& r : m.reals) out << ',' << CsvField(r.name);
  out << ",log_weight,weight";
  const std::vector<std::string> distance_columns = DistanceColumns(m, components);
  for (const std::string& name : distance_columns) out << ',' << name;
  // A multi-fidelity run's multiplier, confirmed (0/1) and cheap distances (low_distance_<c>),
  // last: a single-fidelity run's file keeps its columns.
  const bool fidelity = MultiFidelity(h);
  if (fidelity) {
    out << ",multiplier,confirmed";
    for (const std::string& name : distance_columns) out << ",low_distance_" << name.substr(2);
  }
  // A resample-move run's particles' ancestors (the previous wave's index; -1 drawn afresh), last.
  const bool moves = Moves(h);
  if (moves) out << ",ancestor";
  out << '\n';
  std::string bits;
  for (const WaveRecord& w : h.waves) {
    for (const Particle& p : w.particles) {
      bits.clear();
      for (std::uint8_t bit : p.theta.bits) bits += bit ? '1' : '0';
      out << WaveNumber(w) << ',' << p.index << ',' << bits;
      for (std::uint8_t bit : p.theta.bits) out << ',' << (bit ? '1' : '0');
      for (std::size_t i = 0; i < m.reals.size(); ++i) {
        out << ',' << (i < p.theta.reals.size() ? Number(p.theta.reals[i]) : "NaN");
      }
      out << ',' << Number(p.log_weight) << ',' << Number(p.weight);
      for (std::size_t c = 0; c < components; ++c) {
        out << ',' << (c < p.distance.size() ? Number(p.distance[c]) : "NaN");
      }
      if (fidelity) {
        out << ',' << Number(p.multiplier) << ',' << (p.confirmed ? 1 : 0);
        for (std::size_t c = 0; c < components; ++c) {
          out << ',' << (c < p.low_distance.size() ? Number(p.low_distance[c]) : "NaN");
        }
      }
      if (moves) out << ',' << p.ancestor;
      out << '\n';
    }
  }
}

// Wide: one row per curve; the x of column y_i is row i of positions.csv.
void WriteCurves(OutputDirectory& dir, const RunMetadata& m, const RunHistory& h) {
  const std::string unit = m.position_unit.empty() ? "m" : Identifier(m.position_unit);
  {
    // Named experiments add a last column, experiment (its name): a single experiment's file is
    // as it was before experiments existed.
    const bool named = HasNamedExperiments(m);
    const std::vector<std::string> experiment =
        ExperimentOfEach(ExperimentSlices(m), &ExperimentSlice::outputs, m.output_positions.size());
    std::ostream& out = dir.Add("positions.csv");
    out << "column,position_" << unit << (named ? ",experiment" : "") << '\n';
    for (std::size_t i = 0; i < m.output_positions.size(); ++i) {
      out << "y_" << i << ',' << Number(m.output_positions[i]);
      if (named) out << ',' << CsvField(experiment[i]);
      out << '\n';
    }
  }
  bool any = false;
  for (const WaveRecord& w : h.waves) {
    for (const Particle& p : w.particles) any = any || !p.output.empty();
  }
  if (!any) return;  // the run did not keep outputs
  std::ostream& out = dir.Add("curves.csv");
  out << "wave,index";
  for (std::size_t i = 0; i < m.output_positions.size(); ++i) out << ",y_" << i;
  out << '\n';
  for (const WaveRecord& w : h.waves) {
    for (const Particle& p : w.particles) {
      if (p.output.empty()) continue;
      out << WaveNumber(w) << ',' << p.index;
      for (std::size_t i = 0; i < m.output_positions.size(); ++i) {
        out << ',' << (i < p.output.size() ? Number(p.output[i]) : "NaN");
      }
      out << '\n';
    }
  }
}

void WriteMeasured(OutputDirectory& dir, const RunMetadata& m) {
  const std::string unit = m.position_unit.empty() ? "m" : Identifier(m.position_unit);
  const bool named = HasNamedExperiments(m);
  const std::vector<std::string> experiment = ExperimentOfEach(
      ExperimentSlices(m), &ExperimentSlice::measured, m.measured.positions.size());
  std::ostream& out = dir.Add("measured.csv");
  out << "position_" << unit << ",value" << (named ? ",experiment" : "") << '\n';
  for (std::size_t i = 0; i < m.measured.positions.size(); ++i) {
    out << Number(m.measured.positions[i]) << ',' << Number(m.measured.values[i]);
    if (named) out << ',' << CsvField(experiment[i]);
    out << '\n';
  }
}

// One row per experiment: its index (from 0, as the database's e), name, description, the sizes of
// its slices and where they start (the i of its first y_i column, its first row of measured.csv).
void WriteExperiments(OutputDirectory& dir, const RunMetadata& m) {
  std::ostream& out = dir.Add("experiments.csv");
  out << "index,name,description,outputs,measured,components,first_output,first_measured\n";
  const std::vector<ExperimentSlice> slices = ExperimentSlices(m);
  for (std::size_t e = 0; e < slices.size(); ++e) {
    const ExperimentSlice& x = slices[e];
    out << e << ',' << CsvField(x.name) << ',' << CsvField(x.description) << ',' << x.outputs << ','
        << x.measured << ',' << x.components << ',' << x.first_output << ',' << x.first_measured
        << '\n';
  }
}

// summary.json's "moves" of a resample-move wave (null for a rejection wave of such a run).
std::string MovesJson(const std::optional<WaveMoves>& m) {
  if (!m) return "null";
  return "{\"rounds\": " + std::to_string(m->rounds) +
         ", \"proposed\": " + std::to_string(m->proposed) +
         ", \"accepted\": " + std::to_string(m->accepted) +
         ", \"acceptance_rate\": " + JsonNumber(MoveAcceptance(*m)) +
         ", \"independent_proposed\": " + std::to_string(m->independent_proposed) +
         ", \"independent_accepted\": " + std::to_string(m->independent_accepted) +
         ", \"independent_share\": " + JsonNumber(IndependentShare(*m)) +
         ", \"survivor_ess\": " + JsonNumber(m->survivor_ess) +
         ", \"step\": " + JsonNumber(m->step) + "}";
}

// summary.json's "multi_fidelity": per wave and in total the cheap simulations (every candidate
// ran the cheap simulator), the expensive ones, the seconds each took, and ESS per second of both;
// per wave its continuation probabilities, those tuned for the next wave and the cost ratio
// assumed. The total's ESS per second is the answer's wave's (answer_wave, from 1) over the whole
// run's seconds.
std::string MultiFidelityJson(const RunHistory& h, int answer_wave) {
  std::string out = "{\"waves\": [";
  WaveFidelity total;
  std::int64_t cheap = 0;
  for (std::size_t t = 0; t < h.waves.size(); ++t) {
    const WaveRecord& w = h.waves[t];
    const WaveFidelity f = w.multi_fidelity.value_or(WaveFidelity{});
    cheap += w.candidates;
    total.expensive_simulations += f.expensive_simulations;
    total.cheap_seconds += f.cheap_seconds;
    total.expensive_seconds += f.expensive_seconds;
    out += std::string(t ? "," : "") + "\n    {\"wave\": " + std::to_string(WaveNumber(w)) +
           ", \"continue_if_accepted\": " + JsonNumber(f.continue_if_accepted) +
           ", \"continue_if_rejected\": " + JsonNumber(f.continue_if_rejected) +
           ", \"cheap_simulations\": " + std::to_string(w.candidates) +
           ", \"expensive_simulations\": " + std::to_string(f.expensive_simulations) +
           ", \"cheap_seconds\": " + JsonNumber(f.cheap_seconds) +
           ", \"expensive_seconds\": " + JsonNumber(f.expensive_seconds) +
           ", \"ess_per_second\": " + JsonNumber(w.ess / (f.cheap_seconds + f.expensive_seconds)) +
           ",\n     \"next_continue_if_accepted\": " + JsonNumber(f.next_continue_if_accepted) +
           ", \"next_continue_if_rejected\": " + JsonNumber(f.next_continue_if_rejected) +
           ", \"cost_ratio\": " + JsonNumber(f.cost_ratio) + "}";
  }
  double ess = 0.0;
  for (const WaveRecord& w : h.waves) ess = WaveNumber(w) == answer_wave ? w.ess : ess;
  out +=
      "\n  ], \"total\": {\"cheap_simulations\": " + std::to_string(cheap) +
      ", \"expensive_simulations\": " + std::to_string(total.expensive_simulations) +
      ", \"cheap_seconds\": " + JsonNumber(total.cheap_seconds) +
      ", \"expensive_seconds\": " + JsonNumber(total.expensive_seconds) +
      ", \"ess_per_second\": " + JsonNumber(ess / (total.cheap_seconds + total.expensive_seconds)) +
      "}}";
  return out;
}

void WriteSummary(OutputDirectory& dir,
                  const RunMetadata& m,
                  const RunHistory& h,
                  const ExportOptions& options) {
  const std::vector<std::optional<BitPosition>>& positions = options.bit_positions;
  std::ostream& out = dir.Add("summary.json");
  out << "{\n  \"format\": \"combabc-export\",\n  \"schema_version\": " << m.schema_version
      << ",\n";
  out << "  \"run\": {\n";
  out << "    \"status\": " << JsonString(ToString(m.status)) << ",\n";
  out << "    \"termination\": " << JsonString(m.termination) << ",\n";
  out << "    \"message\": " << JsonString(m.summary_message) << ",\n";
  out << "    \"config_path\": " << JsonString(m.config_path) << ",\n";
  out << "    \"combabc_version\": " << JsonString(m.combabc_version) << ",\n";
  out << "    \"git_hash\": " << JsonString(m.git_hash) << ",\n";
  out << "    \"seed\": " << m.seed << ",\n";
  out << "    \"threads\": " << m.threads << ",\n";
  out << "    \"start_time\": " << JsonString(m.start_time) << ",\n";
  out << "    \"end_time\": " << JsonString(m.end_time) << ",\n";
  out << "    \"resume_count\": " << m.resume_count << ",\n";
  out << "    \"estimator\": " << JsonString(m.estimator) << ",\n";
  out << "    \"dimension\": " << m.dimension << ",\n";
  out << "    \"position_unit\": " << JsonString(m.position_unit) << ",\n";
  out << "    \"waves_completed\": " << h.summary.waves_completed << ",\n";
  out << "    \"simulations\": " << h.summary.simulations << ",\n";
  out << "    \"simulations_discarded\": " << h.summary.simulations_discarded << ",\n";
  out << "    \"failures\": " << h.summary.failures << ",\n";
  out << "    \"wall_seconds\": " << JsonNumber(h.summary.wall_seconds) << "\n  },\n";
  out << "  \"config_text\": " << JsonString(m.config_text) << ",\n";
  out << "  \"bit_names\": [";
  for (std::size_t b = 0; b < static_cast<std::size_t>(m.dimension); ++b) {
    out << (b ? ", " : "") << JsonString(BitName(m, b));
  }
  out << "],\n  \"bit_prior_one\": " << JsonArray(m.bit_prior_one);
  out << ",\n  \"distance_components\": [";
  for (std::size_t c = 0; c < m.distance_components.size(); ++c) {
    const DistanceComponent& dc = m.distance_components[c];
    out << (c ? ", " : "") << "{\"name\": " << JsonString(dc.name)
        << ", \"kind\": " << JsonString(ToString(dc.kind))
        << ", \"required\": " << JsonNumber(dc.required) << "}";
  }
  out << "],\n  \"reals\": [";
  for (std::size_t i = 0; i < m.reals.size(); ++i) {
    const ContinuousPrior& prior = m.reals[i].prior;
    out << (i ? "," : "") << "\n    {\"name\": " << JsonString(m.reals[i].name)
        << ", \"prior\": {\"kind\": " << JsonString(ToString(prior.kind))
        << ", \"low\": " << JsonNumber(prior.low) << ", \"high\": " << JsonNumber(prior.high)
        << ", \"mean\": " << JsonNumber(prior.mean) << ", \"sd\": " << JsonNumber(prior.sd) << "}}";
  }
  const ProposalOptions& p = m.proposal;
  out << (m.reals.empty() ? "" : "\n  ")
      << "],\n  \"proposal\": {\"binary_kernel\": " << JsonString(ToString(p.binary))
      << ", \"logistic\": {\"min_correlation\": " << JsonNumber(p.logistic.min_correlation)
      << ", \"max_predecessors\": " << p.logistic.max_predecessors
      << ", \"ridge\": " << JsonNumber(p.logistic.ridge)
      << ", \"min_marginal\": " << JsonNumber(p.logistic.min_marginal)
      << ", \"clip\": " << JsonNumber(p.logistic.clip) << "}"
      << ", \"continuous_kernel\": " << JsonString(ToString(p.continuous))
      << ", \"scale\": " << JsonNumber(p.scale)
      << ", \"tempering_form\": " << JsonString(m.tempering_form) << "},\n  \"fingerprint\": {";
  for (std::size_t i = 0; i < m.fingerprint.size(); ++i) {
    out << (i ? ", " : "") << JsonString(m.fingerprint[i].first) << ": "
        << JsonString(m.fingerprint[i].second);
  }
  out << "},\n  \"stop_limits\": {";
  for (std::size_t i = 0; i < m.stop_limits.size(); ++i) {
    out << (i ? ", " : "") << JsonString(m.stop_limits[i].first) << ": "
        << JsonString(m.stop_limits[i].second);
  }
  out << "},\n  \"experiments\": [";
  const std::vector<ExperimentSlice> experiments = ExperimentSlices(m);
  for (std::size_t e = 0; e < experiments.size(); ++e) {
    const ExperimentSlice& x = experiments[e];
    out << (e ? "," : "") << "\n    {\"name\": " << JsonString(x.name)
        << ", \"description\": " << JsonString(x.description) << ", \"outputs\": " << x.outputs
        << ", \"measured\": " << x.measured << ", \"components\": " << x.components
        << ", \"first_output\": " << x.first_output << ", \"first_measured\": " << x.first_measured
        << ", \"first_component\": " << x.first_component << "}";
  }
  out << "\n  ],\n  \"waves\": [";
  const bool moves = Moves(h);
  for (std::size_t t = 0; t < h.waves.size(); ++t) {
    const WaveRecord& w = h.waves[t];
    out << (t ? "," : "") << "\n    {\"wave\": " << WaveNumber(w)
        << ", \"thresholds\": " << JsonArray(w.thresholds) << ", \"phi\": " << JsonNumber(w.phi)
        << ", \"candidates\": " << w.candidates << ", \"accepted\": " << w.accepted
        << ", \"failures\": " << w.failures.size()
        << ", \"acceptance_rate\": " << JsonNumber(w.acceptance_rate)
        << ", \"complete\": " << (w.complete ? "true" : "false")
        << ", \"ess\": " << JsonNumber(w.ess) << ", \"distinct\": " << w.distinct
        << ", \"wall_seconds\": " << JsonNumber(w.wall_seconds)
        << ",\n     \"marginals_paper\": " << JsonArray(w.marginals_paper)
        << ",\n     \"marginals_importance\": " << JsonArray(w.marginals_importance)
        << ",\n     \"reals_mean\": " << JsonArray(w.reals_mean)
        << ", \"reals_sd\": " << JsonArray(w.reals_sd) << WaveErrorsJson(ErrorsOf(m, w));
    // A resample-move run's waves only: a rejection run's summary is what it was.
    if (moves) out << ",\n     \"moves\": " << MovesJson(w.moves);
    out << "}";
  }
  const Answer answer = SummariseAnswer(m, h, positions);
  out << "\n  ],";
  if (MultiFidelity(h)) {
    out << "\n  \"multi_fidelity\": " << MultiFidelityJson(h, answer.wave) << ',';
  }
  out << "\n  \"answer\": " << AnswerJson(answer)
      << ",\n  \"strip\": " << (options.strip ? StripJson(*options.strip) : "null")
      << ",\n  \"checks\": " << FitChecksJson(ComputeFitChecks(m, h, options.checks), 2) << "\n}\n";
}

void WriteAll(OutputDirectory& dir, const HistoryStore& store, const ExportOptions& options) {
  const RunMetadata m = store.LoadMetadata();
  const RunHistory h = store.LoadHistory();
  if (options.csv) {
    WriteWaves(dir, m, h);
    WriteMarginals(dir, m, h);
    WritePairCorrelations(dir, m, h);
    if (options.particles) WriteParticles(dir, m, h);
    if (options.curves) WriteCurves(dir, m, h);
    WriteMeasured(dir, m);
    WriteExperiments(dir, m);
    if (options.campaign) WriteCampaignCsv(dir.Add("campaign.csv"), *options.campaign);
  }
  if (options.json) WriteSummary(dir, m, h, options);
}

}  // namespace

void ExportRun(const HistoryStore& store,
               const std::string& out_dir,
               const ExportOptions& options) {
  // Checked before the history is read; the files appear together at Commit().
  OutputDirectory directory(out_dir, options.overwrite);
  WriteAll(directory, store, options);
  if (options.add_files) options.add_files(directory);
  directory.Commit();
}

void ExportRun(const std::string& history_path,
               const std::string& out_dir,
               const ExportOptions& options) {
  const HistoryStore store = HistoryStore::Open(history_path, /*read_only=*/true);
  ExportRun(store, out_dir, options);
}

}  // namespace combabc
