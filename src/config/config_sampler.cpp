// [sampler]: SmcOptions and BinarySpaceOptions (prior, tied clamps).
#include <cmath>
#include <limits>
#include <string>

#include "combabc/config/config.hpp"
#include "combabc/core/error.hpp"
#include "config_reader.hpp"

namespace combabc::config_internal {
namespace {

void ParseTempering(TableReader& s, SmcOptions* smc, Sources* sources) {
  auto t = s.Table("tempering");
  if (!t) return;
  sources->smc["tempering"] = {t->prefix(), t->line()};
  TemperingSchedule& temper = smc->tempering;
  temper.kind = t->Choice<TemperingKind>("kind", "tempering kind").value_or(temper.kind);
  temper.form = t->Choice<TemperingForm>("form", "tempering form").value_or(temper.form);
  temper.phi0 = t->NumberIn("phi0", temper.phi0, 0.0, 1.0);
  if (const auto values = t->Numbers("values")) {
    if (temper.kind != TemperingKind::kList) t->Fail("values", "only used with kind = \"list\"");
    for (std::size_t i = 0; i < values->size(); ++i) {
      if (!((*values)[i] >= 0.0 && (*values)[i] <= 1.0)) {
        t->Fail("values", "values[" + std::to_string(i) + "] must be in [0, 1]");
      }
    }
    temper.values = *values;
    Note(sources->smc, "tempering", *t, "values");
  } else if (temper.kind == TemperingKind::kList) {
    t->Fail("values", "kind = \"list\" needs values = [phi for waves 1, 2, ...]");
  }
  t->Finish();
}

// [sampler.multi_fidelity]: MultiFidelityOptions (a run with [simulator.low_fidelity] only).
void ParseMultiFidelity(TableReader& s, MultiFidelityOptions* mf, Sources* sources) {
  auto t = s.Table("multi_fidelity");
  if (!t) return;
  sources->multi_fidelity = Source{t->prefix(), t->line()};
  auto probability = [&](const char* key, double* value) {
    if (const auto v = t->Number(key)) {
      if (!(*v > 0.0 && *v <= 1.0)) t->Fail(key, "must be in (0, 1]");
      *value = *v;
    }
  };
  probability("continue_if_accepted", &mf->continue_if_accepted);
  probability("continue_if_rejected", &mf->continue_if_rejected);
  mf->adapt = t->Bool("adapt").value_or(mf->adapt);
  probability("floor", &mf->floor);
  if (const auto ratio = t->Number("cost_ratio")) {
    if (!(*ratio > 0.0) || !std::isfinite(*ratio)) {
      t->Fail("cost_ratio", "must be finite and > 0 (leave it out to measure the ratio)");
    }
    mf->cost_ratio = *ratio;
  }
  t->Finish();
}

// [sampler.moves]: MoveOptions, a resample-move run's only (method = "resample_move"); each key
// checked against MoveOptions::IsValid's range here, so that the error names the key.
void ParseMoves(TableReader& s, SamplerMethod method, MoveOptions* moves, Sources* sources) {
  auto t = s.Table("moves");
  if (!t) return;
  sources->moves = Source{t->prefix(), t->line()};
  sources->smc["moves"] = *sources->moves;
  if (method != SamplerMethod::kResampleMove) {
    throw Error(ErrorKind::kConfig,
                "move options apply to resample-move runs only; set method = \"resample_move\" "
                "in [sampler] or remove [sampler.moves]",
                t->path(),
                t->line(),
                t->prefix());
  }
  // A fraction strictly between 0 and 1.
  auto open_fraction = [&](const char* key, double* value) {
    if (const auto v = t->Number(key)) {
      if (!(*v > 0.0 && *v < 1.0)) t->Fail(key, "must be in (0, 1)");
      *value = *v;
    }
  };
  open_fraction("ess_fraction", &moves->ess_fraction);
  open_fraction("stay_probability", &moves->stay_probability);
  moves->max_rounds = t->IntegerIn("max_rounds", moves->max_rounds, 1, 10000);
  moves->independent_share = t->NumberIn("independent_share", moves->independent_share, 0.0, 1.0);
  open_fraction("min_survivor_fraction", &moves->min_survivor_fraction);
  if (const auto final_wave = t->Choice<FinalWave>("final_wave", "final wave")) {
    moves->final_wave = *final_wave;
  }
  t->Finish();
}

void ParseTies(TableReader& s, int dimension, BinarySpaceOptions* space) {
  const toml::node* node = s.Raw("tie");
  if (!node) return;
  const std::string key = s.Key("tie");
  const std::string expected =
      "expected an array of groups of 1-based clamp numbers, e.g. "
      "[[1, 19], [2, 20]]";
  if (!node->is_array()) s.FailAt(*node, key, expected + ", got " + TypeName(*node));
  const toml::array& groups = *node->as_array();
  std::vector<int> group_of(static_cast<std::size_t>(dimension), -1);
  for (std::size_t g = 0; g < groups.size(); ++g) {
    const std::string gkey = key + "[" + std::to_string(g) + "]";
    if (!groups[g].is_array()) s.FailAt(groups[g], gkey, expected);
    const toml::array& group = *groups[g].as_array();
    if (group.size() < 2) s.FailAt(groups[g], gkey, "a tie needs at least 2 clamps");
    std::vector<int> bits;
    for (std::size_t i = 0; i < group.size(); ++i) {
      const std::string ekey = gkey + "[" + std::to_string(i) + "]";
      if (!group[i].is_integer()) {
        s.FailAt(group[i], ekey, std::string("expected an integer, got ") + TypeName(group[i]));
      }
      const std::int64_t clamp = group[i].as_integer()->get();
      if (clamp < 1 || clamp > dimension) {
        s.FailAt(group[i],
                 ekey,
                 "clamp " + std::to_string(clamp) + " is out of range; must be in [1, " +
                     std::to_string(dimension) + "]");
      }
      const auto bit = static_cast<int>(clamp - 1);
      if (group_of[bit] >= 0) {
        s.FailAt(group[i],
                 ekey,
                 "clamp " + std::to_string(clamp) + " is already tied in tie[" +
                     std::to_string(group_of[bit]) + "]; groups must be disjoint");
      }
      group_of[bit] = static_cast<int>(g);
      bits.push_back(bit);
    }
    space->tied.push_back(std::move(bits));
  }
}

}  // namespace

void ParseSamplerSection(TableReader& root, CalibrationConfig* c, Sources* sources) {
  SmcOptions& smc = c->smc;
  BinarySpaceOptions& space = c->space;
  const int dimension = static_cast<int>(space.names.size());
  space.dimension = dimension;
  auto t = root.Table("sampler");
  if (!t) return;  // all defaults
  sources->sampler = {t->prefix(), t->line()};
  smc.num_waves = t->IntegerIn("waves", smc.num_waves, 1, 1000000);
  Note(sources->smc, "num_waves", *t, "waves");
  // accepted_per_wave: one n for every wave, or a list of n_t, one per wave.
  const toml::node* accepted = t->Raw("accepted_per_wave");
  if (accepted && accepted->is_array()) {
    const toml::array& list = *accepted->as_array();
    if (static_cast<int>(list.size()) != smc.num_waves) {
      t->Fail("accepted_per_wave",
              "has " + std::to_string(list.size()) +
                  " entries; a list needs one per wave (waves = " + std::to_string(smc.num_waves) +
                  ")");
    }
    for (std::size_t i = 0; i < list.size(); ++i) {
      const auto n = list[i].value<std::int64_t>();
      if (!list[i].is_integer() || !n || *n < 1 || *n > 1000000000) {
        t->FailAt(list[i],
                  "sampler.accepted_per_wave[" + std::to_string(i) + "]",
                  "must be an integer in [1, 1000000000]");
      }
      smc.accepted_by_wave.push_back(static_cast<int>(*n));
    }
  } else if (accepted) {
    smc.accepted_per_wave = t->IntegerIn("accepted_per_wave", smc.accepted_per_wave, 1, 1000000000);
  }
  Note(sources->smc, "accepted_per_wave", *t, "accepted_per_wave");
  smc.estimator = t->Choice<Estimator>("estimator", "estimator").value_or(smc.estimator);
  if (const auto seed = t->Integer("seed")) {
    if (*seed < 0) t->Fail("seed", "must be >= 0");
    smc.seed = static_cast<std::uint64_t>(*seed);
  }
  smc.threads = t->IntegerIn("threads", smc.threads, 0, 4096);
  Note(sources->smc, "threads", *t, "threads");
  if (const auto max_simulations = t->Integer("max_simulations")) {
    if (*max_simulations < 0) t->Fail("max_simulations", "must be >= 0 (0 = no limit)");
    smc.max_simulations = *max_simulations;
  }
  Note(sources->smc, "max_simulations", *t, "max_simulations");
  smc.min_acceptance_rate = t->NumberIn("min_acceptance_rate", smc.min_acceptance_rate, 0.0, 1.0);
  Note(sources->smc, "min_acceptance_rate", *t, "min_acceptance_rate");
  auto count = [&](const char* key, std::int64_t* field) {
    if (const auto value = t->Integer(key)) {
      if (*value < 1) t->Fail(key, "must be >= 1");
      *field = *value;
    }
  };
  count("acceptance_floor_after", &smc.acceptance_floor_after);
  Note(sources->smc, "acceptance_floor_after", *t, "acceptance_floor_after");
  smc.max_failure_fraction =
      t->NumberIn("max_failure_fraction", smc.max_failure_fraction, 0.0, 1.0);
  Note(sources->smc, "max_failure_fraction", *t, "max_failure_fraction");
  count("failure_fraction_after", &smc.failure_fraction_after);
  Note(sources->smc, "failure_fraction_after", *t, "failure_fraction_after");
  smc.max_wall_time_s = t->NumberIn("max_wall_time", smc.max_wall_time_s, 0.0, kHuge);
  Note(sources->smc, "max_wall_time_s", *t, "max_wall_time");
  smc.batch_size = t->IntegerIn("batch_size", smc.batch_size, 0, 1000000000);
  Note(sources->smc, "batch_size", *t, "batch_size");
  ParseTempering(*t, &smc, sources);
  ParseMultiFidelity(*t, &smc.multi_fidelity, sources);
  if (const auto method = t->Choice<SamplerMethod>("method", "sampler method")) {
    smc.method = *method;
    sources->method = Source{t->Key("method"), t->Line("method")};
    Note(sources->smc, "method", *t, "method");
  }
  ParseMoves(*t, smc.method, &smc.moves, sources);

  if (const toml::node* prior = t->Raw("prior")) {
    const std::string key = t->Key("prior");
    Note(sources->space, "default_prior_one", *t, "prior");
    Note(sources->space, "prior_one", *t, "prior");
    auto probability = [&](const toml::node& n, const std::string& where) {
      if (!n.is_number()) {
        t->FailAt(n, where, std::string("expected a probability, got ") + TypeName(n));
      }
      const double p = n.value<double>().value_or(-1.0);
      if (!(p >= 0.0 && p <= 1.0)) t->FailAt(n, where, "must be in [0, 1]");
      return p;
    };
    if (prior->is_array()) {
      const toml::array& a = *prior->as_array();
      if (static_cast<int>(a.size()) != dimension) {
        t->FailAt(*prior,
                  key,
                  "has " + std::to_string(a.size()) + " entries; must have one per bit (" +
                      std::to_string(dimension) + ")");
      }
      space.prior_one.clear();
      for (std::size_t i = 0; i < a.size(); ++i) {
        space.prior_one.push_back(probability(a[i], key + "[" + std::to_string(i) + "]"));
      }
    } else {
      space.default_prior_one = probability(*prior, key);
    }
  }
  Note(sources->space, "tied", *t, "tie");
  ParseTies(*t, dimension, &space);
  t->Finish();
}

}  // namespace combabc::config_internal
