#include "history_arrays.hpp"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <cmath>
#include <cstdint>

#include "combabc/export/export.hpp"
#include "combabc/samplers/monte_carlo_error.hpp"

namespace py = pybind11;

namespace combabc::python {
namespace {

py::array_t<double> Vector(const std::vector<double>& v) {
  return py::array_t<double>(static_cast<py::ssize_t>(v.size()), v.data());
}

// A multi-fidelity wave's continuation probabilities and costs ("multi_fidelity", a dict) and its
// particles' multiplier float64[n], confirmed bool[n] and low_distance float64[n, k]; None for
// each in a single-fidelity run.
void AddFidelity(const WaveRecord& wave, py::ssize_t num_components, py::dict& d) {
  if (!wave.multi_fidelity) {
    for (const char* key : {"multi_fidelity", "multiplier", "confirmed", "low_distance"}) {
      d[key] = py::none();
    }
    return;
  }
  const WaveFidelity& f = *wave.multi_fidelity;
  py::dict fidelity;
  fidelity["continue_if_accepted"] = f.continue_if_accepted;
  fidelity["continue_if_rejected"] = f.continue_if_rejected;
  fidelity["expensive_simulations"] = f.expensive_simulations;
  fidelity["cheap_seconds"] = f.cheap_seconds;
  fidelity["expensive_seconds"] = f.expensive_seconds;
  fidelity["next_continue_if_accepted"] = f.next_continue_if_accepted;
  fidelity["next_continue_if_rejected"] = f.next_continue_if_rejected;
  fidelity["cost_ratio"] = f.cost_ratio;
  d["multi_fidelity"] = fidelity;
  const auto n = static_cast<py::ssize_t>(wave.particles.size());
  py::array_t<double> multiplier(n);
  py::array_t<bool> confirmed(n);
  py::array_t<double> low_distance({n, num_components});
  auto multiplier_w = multiplier.mutable_unchecked<1>();
  auto confirmed_w = confirmed.mutable_unchecked<1>();
  auto low_w = low_distance.mutable_unchecked<2>();
  for (py::ssize_t i = 0; i < n; ++i) {
    const Particle& p = wave.particles[static_cast<std::size_t>(i)];
    multiplier_w(i) = p.multiplier;
    confirmed_w(i) = p.confirmed;
    for (py::ssize_t k = 0; k < num_components; ++k) {
      const auto j = static_cast<std::size_t>(k);
      low_w(i, k) = j < p.low_distance.size() ? p.low_distance[j] : std::nan("");
    }
  }
  d["multiplier"] = multiplier;
  d["confirmed"] = confirmed;
  d["low_distance"] = low_distance;
}

// A resample-move wave's move statistics ("moves", a dict under summary.json's names; None for a
// rejection wave) and its particles' ancestors (int64[n]: the previous wave's index, -1 drawn
// afresh).
void AddMoves(const WaveRecord& wave, py::dict& d) {
  const auto n = static_cast<py::ssize_t>(wave.particles.size());
  py::array_t<std::int64_t> ancestor(n);
  auto ancestor_w = ancestor.mutable_unchecked<1>();
  for (py::ssize_t i = 0; i < n; ++i) {
    ancestor_w(i) = wave.particles[static_cast<std::size_t>(i)].ancestor;
  }
  d["ancestor"] = ancestor;
  if (!wave.moves) {
    d["moves"] = py::none();
    return;
  }
  const WaveMoves& m = *wave.moves;
  const double nan = std::nan("");
  const auto rate = [&](std::int64_t part) {
    return m.proposed > 0 ? static_cast<double>(part) / static_cast<double>(m.proposed) : nan;
  };
  py::dict moves;
  moves["rounds"] = m.rounds;
  moves["proposed"] = m.proposed;
  moves["accepted"] = m.accepted;
  moves["acceptance_rate"] = rate(m.accepted);
  moves["independent_proposed"] = m.independent_proposed;
  moves["independent_accepted"] = m.independent_accepted;
  moves["independent_share"] = rate(m.independent_proposed);
  moves["survivor_ess"] = m.survivor_ess;
  moves["step"] = m.step;
  d["moves"] = moves;
}

// A wave's Monte-Carlo errors (WaveMonteCarloErrors), under summary.json's names: per bit its
// standard error and ESS, the bits' ESS (NaN when no bit varies), per real its mean's and sd's
// standard errors and its mean's ESS. An enumeration's numbers are exact: NaN each.
void AddErrors(const WaveRecord& wave, const HistoryNames& names, py::dict& d) {
  const WaveErrors e = names.exact ? WaveErrors{} : WaveMonteCarloErrors(wave, names.bit_prior_one);
  const double nan = std::nan("");
  std::vector<double> se(wave.marginals_paper.size(), nan);
  std::vector<double> ess(se.size(), nan);
  for (std::size_t b = 0; b < e.bits.size() && b < se.size(); ++b) {
    se[b] = e.bits[b].se;
    ess[b] = e.bits[b].ess;
  }
  std::vector<double> mean_se(wave.reals_mean.size(), nan);
  std::vector<double> sd_se(mean_se.size(), nan);
  std::vector<double> reals_ess(mean_se.size(), nan);
  for (std::size_t r = 0; r < e.real_means.size() && r < mean_se.size(); ++r) {
    mean_se[r] = e.real_means[r].se;
    sd_se[r] = e.real_sds[r].se;
    reals_ess[r] = e.real_means[r].ess;
  }
  d["marginals_se"] = Vector(se);
  d["marginals_ess"] = Vector(ess);
  d["ess_bits"] = e.bits_ess.value_or(nan);
  d["reals_mean_se"] = Vector(mean_se);
  d["reals_sd_se"] = Vector(sd_se);
  d["reals_ess"] = Vector(reals_ess);
}

py::dict WaveToDict(const WaveRecord& wave, const HistoryNames& names) {
  py::dict d;
  d["number"] = wave.wave + 1;  // waves count from 1 wherever a user sees them
  d["thresholds"] = Vector(wave.thresholds);
  d["phi"] = wave.phi;
  d["proposal"] = Vector(wave.proposal);
  d["candidates"] = wave.candidates;
  d["accepted"] = wave.accepted;
  d["acceptance_rate"] = wave.acceptance_rate;
  d["complete"] = wave.complete;
  d["marginals_paper"] = Vector(wave.marginals_paper);
  d["marginals_importance"] = Vector(wave.marginals_importance);
  d["ess"] = wave.ess;
  d["reals_mean"] = Vector(wave.reals_mean);
  d["reals_sd"] = Vector(wave.reals_sd);
  AddErrors(wave, names, d);
  d["distinct"] = wave.distinct;
  d["discarded"] = wave.discarded;
  d["wall_seconds"] = wave.wall_seconds;
  // d x d (PairCorrelations of the particles), or 0 x 0 for a wave without particles or with
  // more than kMaxPairCorrelationBits bits.
  const auto pairs =
      static_cast<py::ssize_t>(wave.particles.empty() || wave.pair_correlations.empty()
                                   ? 0
                                   : wave.particles.front().theta.bits.size());
  d["pair_correlations"] = py::array_t<double>({pairs, pairs}, wave.pair_correlations.data());

  const auto n = static_cast<py::ssize_t>(wave.particles.size());
  const auto num_bits = static_cast<py::ssize_t>(names.bits.size());
  const auto num_reals = static_cast<py::ssize_t>(names.reals.size());
  const auto num_components = static_cast<py::ssize_t>(names.components.size());
  // Every particle keeps its output, or none does (SmcOptions::keep_outputs).
  const auto num_outputs =
      static_cast<py::ssize_t>(n > 0 ? wave.particles.front().output.size() : 0);
  py::array_t<std::int64_t> index(n);
  py::array_t<std::uint8_t> bits({n, num_bits});
  py::array_t<double> reals({n, num_reals});
  py::array_t<double> log_weight(n);
  py::array_t<double> weight(n);
  py::array_t<double> distance({n, num_components});
  py::array_t<double> output({n, num_outputs});
  auto index_w = index.mutable_unchecked<1>();
  auto bits_w = bits.mutable_unchecked<2>();
  auto reals_w = reals.mutable_unchecked<2>();
  auto log_weight_w = log_weight.mutable_unchecked<1>();
  auto weight_w = weight.mutable_unchecked<1>();
  auto distance_w = distance.mutable_unchecked<2>();
  auto output_w = output.mutable_unchecked<2>();
  for (py::ssize_t i = 0; i < n; ++i) {
    const Particle& p = wave.particles[static_cast<std::size_t>(i)];
    index_w(i) = p.index;
    for (py::ssize_t k = 0; k < num_bits; ++k) {
      bits_w(i, k) = p.theta.bits[static_cast<std::size_t>(k)];
    }
    for (py::ssize_t k = 0; k < num_reals; ++k) {
      reals_w(i, k) = p.theta.reals[static_cast<std::size_t>(k)];
    }
    log_weight_w(i) = p.log_weight;
    weight_w(i) = p.weight;
    for (py::ssize_t k = 0; k < num_components; ++k) {
      distance_w(i, k) = p.distance[static_cast<std::size_t>(k)];
    }
    for (py::ssize_t k = 0; k < num_outputs; ++k) {
      const auto j = static_cast<std::size_t>(k);
      output_w(i, k) = j < p.output.size() ? p.output[j] : std::nan("");
    }
  }
  d["index"] = index;
  d["bits"] = bits;
  d["reals"] = reals;
  d["log_weight"] = log_weight;
  d["weight"] = weight;
  d["distance"] = distance;
  d["output"] = output;
  py::array_t<std::int64_t> failure_index(static_cast<py::ssize_t>(wave.failures.size()));
  py::list failure_reason;
  auto failure_w = failure_index.mutable_unchecked<1>();
  for (std::size_t i = 0; i < wave.failures.size(); ++i) {
    failure_w(static_cast<py::ssize_t>(i)) = wave.failures[i].index;
    failure_reason.append(wave.failures[i].reason);
  }
  d["failure_index"] = failure_index;
  d["failure_reason"] = failure_reason;
  // The mode-loss diagnostic's classes (docs/algorithm.md, "Mode loss").
  py::list classes;
  for (const PatternClass& c : wave.pattern_classes) {
    py::dict one;
    one["bits"] = py::array_t<std::uint8_t>(static_cast<py::ssize_t>(c.bits.size()), c.bits.data());
    one["mass"] = c.mass;
    one["proposal"] = c.proposal;
    one["flagged"] = c.flagged;
    classes.append(one);
  }
  d["pattern_classes"] = classes;
  // The CLI's line for the wave's flagged classes ("" for none), which run and resume raise as a
  // combabc.ModeLossWarning.
  d["mode_loss_warning"] = ModeLossWarning(wave);
  AddFidelity(wave, num_components, d);
  AddMoves(wave, d);
  return d;
}

}  // namespace

py::dict HistoryToDict(const RunHistory& history, const HistoryNames& names) {
  py::dict result;
  py::dict name_lists;
  name_lists["bits"] = names.bits;
  name_lists["reals"] = names.reals;
  name_lists["components"] = names.components;
  name_lists["threshold_columns"] = names.threshold_columns;
  name_lists["distance_columns"] = names.distance_columns;
  result["names"] = name_lists;
  result["estimator"] = names.estimator;
  py::dict proposal;
  proposal["binary_kernel"] = names.binary_kernel;
  proposal["continuous_kernel"] = names.continuous_kernel;
  result["proposal"] = proposal;
  const RunSummary& s = history.summary;
  py::dict summary;
  summary["termination"] = std::string(ToString(s.termination));
  summary["message"] = s.message;
  summary["waves_completed"] = s.waves_completed;
  summary["simulations"] = s.simulations;
  summary["simulations_discarded"] = s.simulations_discarded;
  summary["failures"] = s.failures;
  summary["wall_seconds"] = s.wall_seconds;
  result["summary"] = summary;
  py::list waves;
  for (const WaveRecord& wave : history.waves) waves.append(WaveToDict(wave, names));
  result["waves"] = waves;
  return result;
}

py::list ExperimentsToList(const RunMetadata& metadata) {
  py::list experiments;
  for (const ExperimentSlice& x : ExperimentSlices(metadata)) {
    py::dict d;
    d["name"] = x.name;
    d["description"] = x.description;
    d["first_output"] = x.first_output;
    d["outputs"] = x.outputs;
    d["first_measured"] = x.first_measured;
    d["measured"] = x.measured;
    d["first_component"] = x.first_component;
    d["components"] = x.components;
    experiments.append(d);
  }
  return experiments;
}

}  // namespace combabc::python
