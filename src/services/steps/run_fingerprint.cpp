#include "services/steps/run_fingerprint.hpp"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <map>

#include "combabc/core/error.hpp"
#include "combabc/core/fnv1a.hpp"

namespace combabc::services {
namespace {

// FNV-1a 64 over a canonical text: every field as "name=value;", doubles with 17 significant
// digits (exact round trip), so equal inputs give equal digests on every platform.
class Canonical {
 public:
  Canonical& Add(const char* name, double value) {
    char text[32];
    std::snprintf(text, sizeof text, "%.17g", value);
    return Add(name, std::string(text));
  }
  Canonical& Add(const char* name, long long value) { return Add(name, std::to_string(value)); }
  Canonical& Add(const char* name, int value) { return Add(name, std::to_string(value)); }
  Canonical& Add(const char* name, bool value) { return Add(name, std::string(value ? "1" : "0")); }
  Canonical& Add(const char* name, const char* value) { return Add(name, std::string(value)); }
  Canonical& Add(const char* name, const std::string& value) {
    // The length first: no two different field lists serialise alike.
    text_ += name;
    text_ += '=';
    text_ += std::to_string(value.size());
    text_ += ':';
    text_ += value;
    text_ += ';';
    return *this;
  }
  Canonical& Add(const char* name, std::span<const double> values) {
    Add(name, static_cast<long long>(values.size()));
    for (double v : values) Add(name, v);
    return *this;
  }
  std::string Digest() const {
    const std::uint64_t hash =
        Fnv1a({reinterpret_cast<const unsigned char*>(text_.data()), text_.size()});
    char text[17];
    std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(hash));
    return text;
  }

 private:
  std::string text_;
};

void AddThreshold(Canonical& c, const ThresholdSchedule& t) {
  c.Add("threshold.kind", static_cast<int>(t.kind))
      .Add("threshold.values", t.values)
      .Add("threshold.quantile", t.quantile)
      .Add("threshold.initial", t.initial)
      .Add("threshold.target", t.target);
  // The newer kinds' fields only where they apply, so that earlier runs keep their digest.
  if (t.weighted) c.Add("threshold.weighted", true);
  if (t.kind == ThresholdKind::kAcceptance) c.Add("threshold.acceptance_rate", t.acceptance_rate);
  if (t.kind == ThresholdKind::kEss) c.Add("threshold.ess_fraction", t.ess_fraction);
}

// What decides the sequence of candidates and acceptances. Not threads or batch_size (the history
// does not depend on them) nor max_wall_time_s (wall time is not reproducible anyway).
std::string SamplerPart(const SmcOptions& s) {
  Canonical c;
  c.Add("num_waves", s.num_waves).Add("accepted_per_wave", s.accepted_per_wave);
  // Only when given, so that earlier runs keep their digest and resume.
  for (const int n : s.accepted_by_wave) c.Add("accepted_by_wave", n);
  c.Add("thresholds", static_cast<int>(s.thresholds.size()));
  for (const ThresholdSchedule& t : s.thresholds) AddThreshold(c, t);
  c.Add("tempering.kind", ToString(s.tempering.kind))
      .Add("tempering.form", ToString(s.tempering.form))
      .Add("tempering.phi0", s.tempering.phi0)
      .Add("tempering.values", s.tempering.values);
  const ProposalOptions& p = s.proposal;
  c.Add("proposal.binary", ToString(p.binary))
      .Add("logistic.min_correlation", p.logistic.min_correlation)
      .Add("logistic.max_predecessors", p.logistic.max_predecessors)
      .Add("logistic.ridge", p.logistic.ridge)
      .Add("logistic.min_marginal", p.logistic.min_marginal)
      .Add("logistic.clip", p.logistic.clip)
      .Add("proposal.continuous", ToString(p.continuous))
      .Add("proposal.scale", p.scale);
  c.Add("estimator", ToString(s.estimator))
      .Add("seed", std::to_string(s.seed))
      .Add("max_simulations", static_cast<long long>(s.max_simulations))
      .Add("min_acceptance_rate", s.min_acceptance_rate)
      .Add("acceptance_floor_after", static_cast<long long>(s.acceptance_floor_after))
      .Add("max_failure_fraction", s.max_failure_fraction)
      .Add("failure_fraction_after", static_cast<long long>(s.failure_fraction_after))
      .Add("keep_outputs", s.keep_outputs);
  // A resample-move run only: a rejection run's digest is what it was before the method existed,
  // so that its histories still resume (its move options are unused, and refused in a config).
  if (s.method != SamplerMethod::kRejection) {
    const MoveOptions& m = s.moves;
    c.Add("method", ToString(s.method))
        .Add("moves.ess_fraction", m.ess_fraction)
        .Add("moves.stay_probability", m.stay_probability)
        .Add("moves.max_rounds", m.max_rounds)
        .Add("moves.independent_share", m.independent_share)
        .Add("moves.min_survivor_fraction", m.min_survivor_fraction)
        .Add("moves.final_wave", ToString(m.final_wave));
  }
  return c.Digest();
}

// Bits: dimension, ties (which free parameter drives each bit) and the prior; names too, as the
// history and its reports show them. Reals: names and priors.
std::string SpacePart(const ParameterSpace& space) {
  Canonical c;
  const BinarySpace& bits = space.binary();
  c.Add("dimension", bits.dimension()).Add("free", bits.num_free());
  for (int k = 0; k < bits.dimension(); ++k) {
    c.Add("bit.name", bits.name(k)).Add("bit.free_of", bits.free_of_bit(k));
  }
  c.Add("free_prior_one", bits.free_prior_one());
  c.Add("reals", space.num_reals());
  for (const ContinuousParameter& r : space.reals()) {
    c.Add("real.name", r.name)
        .Add("real.kind", ToString(r.prior.kind))
        .Add("real.low", r.prior.low)
        .Add("real.high", r.prior.high)
        .Add("real.mean", r.prior.mean)
        .Add("real.sd", r.prior.sd);
  }
  // Joint priors only when there are any, so that earlier runs keep their digest and resume. A
  // custom prior's code cannot be hashed: its kJoint reals' sampled moments above stand for it.
  if (!space.joint_priors().empty()) c.Add("joint", static_cast<int>(space.joint_priors().size()));
  for (const JointPriorGroup& g : space.joint_priors()) {
    for (const std::string& name : g.names) c.Add("joint.name", name);
    c.Add("joint.prior", g.prior->Describe());
  }
  return c.Digest();
}

// A config without [[experiment]] tables hashes as it did before experiments existed, so that its
// runs still resume; named experiments add their names.
std::string DataPart(const CalibrationConfig& config, std::span<const MeasuredProfile> data) {
  Canonical c;
  for (std::size_t e = 0; e < data.size(); ++e) {
    const ExperimentConfig& x = config.experiments.at(e);
    if (x.line != 0) c.Add("experiment", x.name);
    c.Add("positions", data[e].positions).Add("values", data[e].values);
  }
  return c.Digest();
}

// The components as configured and as built (names, kinds, required), and the normalisation of
// the simulated profiles the metric applies.
std::string MetricPart(const CalibrationConfig& config,
                       const std::vector<DistanceComponent>& components) {
  Canonical c;
  c.Add("normalise", config.experiments.front().data.normalise);
  for (const ExperimentConfig& x : config.experiments) {
    if (x.line != 0) c.Add("experiment", x.name);
    for (const MetricComponentConfig& m : x.metric.components) {
      c.Add("type", ToString(m.type)).Add("from", m.from).Add("to", m.to).Add("name", m.name);
    }
  }
  for (const DistanceComponent& d : components) {
    c.Add("component", d.name).Add("kind", static_cast<int>(d.kind)).Add("required", d.required);
  }
  return c.Digest();
}

// The built-in sensor simulator: every SensorOptions key that changes its output.
// memory_limit_bytes only decides whether the model may be built.
std::string SimulatorPart(const CalibrationConfig& config, const plate::SensorOptions& s) {
  Canonical c;
  c.Add("simulator", "combabc sensor plate");
  c.Add("length", s.length).Add("width", s.width);
  for (const plate::Layer& layer : s.layers) {
    c.Add("layer.thickness", layer.thickness)
        .Add("layer.youngs_modulus", layer.youngs_modulus)
        .Add("layer.poisson_ratio", layer.poisson_ratio)
        .Add("layer.density", layer.density)
        .Add("layer.loss_factor", layer.loss_factor);
  }
  c.Add("foundation_stiffness", s.foundation_stiffness)
      .Add("foundation_loss_factor", s.foundation_loss_factor)
      .Add("clamps_per_edge", s.clamps_per_edge)
      .Add("fixed_support", static_cast<int>(s.fixed_support))
      .Add("short_edge_start", static_cast<int>(s.short_edge_start))
      .Add("short_edge_end", static_cast<int>(s.short_edge_end));
  // Each experiment's load and scan, in the order one experiment always had them.
  for (const ExperimentConfig& x : config.experiments) {
    if (x.line != 0) c.Add("experiment", x.name);
    const plate::LoadCase& l = x.load;
    c.Add("load_force", l.load_force)
        .Add("load_x", l.load_x)
        .Add("load_y_fraction", l.load_y_fraction)
        .Add("load_patch_length", l.load_patch_length)
        .Add("load_patch_width", l.load_patch_width)
        .Add("frequency_hz", x.frequency_hz)
        .Add("output_positions", l.output_positions)
        .Add("output_y_fraction", l.output_y_fraction);
  }
  c.Add("normalise", s.normalise)
      .Add("elements_per_section", s.elements_per_section)
      .Add("elements_across_width", s.ElementsAcrossWidth())
      .Add("length_grading", s.length_grading)
      .Add("width_grading", s.WidthGrading())
      .Add("always_pivot", s.always_pivot);
  // Added only when not the original Kirchhoff model, so histories written before the key
  // existed keep their fingerprint.
  if (s.theory != plate::PlateTheory::kKirchhoff) c.Add("theory", static_cast<int>(s.theory));
  // Likewise only when not the original bilinear order.
  if (s.ElementOrder() != 1) c.Add("element_order", s.ElementOrder());
  return c.Digest();
}

// An external simulator: what the config says about the program and how it is called (the
// timeout and retries decide which candidates fail, so they decide the history too).
std::string ExternalPart(const CalibrationConfig& config, const SimulatorConfig& s) {
  const ExternalSimulatorOptions& e = s.external;
  Canonical c;
  // Named experiments tell the program their loads: those decide its outputs too.
  for (const ExperimentConfig& x : config.experiments) {
    if (x.line == 0) continue;
    c.Add("experiment", x.name)
        .Add("load_x", x.load.load_x)
        .Add("load_y_fraction", x.load.load_y_fraction)
        .Add("load_force", x.load.load_force)
        .Add("frequency_hz", x.frequency_hz);
  }
  c.Add("simulator", ToString(s.kind));
  c.Add("argv", static_cast<int>(e.argv.size()));
  for (const std::string& a : e.argv) c.Add("arg", a);
  c.Add("timeout_s", e.timeout_s).Add("retries", e.retries);
  if (s.kind == SimulatorKind::kCommand) {
    c.Add("params", ToString(e.params))
        .Add("params_format", ToString(e.params_format))
        .Add("results", ToString(e.results))
        .Add("results_format", ToString(e.results_format));
  }
  return c.Digest();
}

std::string OutputsPart(const SimulatorOutputs& o) {
  Canonical c;
  c.Add("name", o.name).Add("coordinates", o.coordinates);
  return c.Digest();
}

// A multi-fidelity run's cheap simulator (as the parts above describe the expensive one), the
// outputs it stands for, and the multi-fidelity options. Absent from single-fidelity runs, so
// their fingerprints are what they were.
std::string LowFidelityPart(const CalibrationConfig& config, const std::string& handshake) {
  const LowFidelityConfig& low = *config.low_fidelity;
  const bool sensor = low.simulator.kind == SimulatorKind::kSensor;
  Canonical c;
  c.Add("simulator",
        sensor ? SimulatorPart(config, low.model) : ExternalPart(config, low.simulator));
  if (!sensor) c.Add("outputs", OutputsPart(low.simulator.outputs));
  if (low.simulator.kind == SimulatorKind::kWorker) c.Add("handshake", handshake);
  c.Add("output_map", static_cast<long long>(low.output_map.size()));
  for (int k : low.output_map) c.Add("pick", k);
  const MultiFidelityOptions& mf = config.smc.multi_fidelity;
  c.Add("continue_if_accepted", mf.continue_if_accepted)
      .Add("continue_if_rejected", mf.continue_if_rejected)
      .Add("adapt", mf.adapt)
      .Add("floor", mf.floor)
      .Add("cost_ratio", mf.cost_ratio);
  return c.Digest();
}

}  // namespace

Fingerprint ComputeFingerprint(const FingerprintInputs& in) {
  const SimulatorConfig& simulator = in.config->simulator;
  const bool sensor = simulator.kind == SimulatorKind::kSensor;
  // The sensor's part is what it always was, so runs started before external simulators existed
  // still resume; its outputs are its [model.output] positions, already in that part.
  Fingerprint parts = {
      {"sampler", SamplerPart(in.config->smc)},
      {"space", SpacePart(*in.space)},
      {"data", DataPart(*in.config, in.data)},
      {"metric", MetricPart(*in.config, in.components)},
      {"simulator",
       sensor ? SimulatorPart(*in.config, in.config->model) : ExternalPart(*in.config, simulator)},
  };
  if (!sensor) parts.emplace_back("simulator_outputs", OutputsPart(simulator.outputs));
  if (simulator.kind == SimulatorKind::kWorker) {
    parts.emplace_back("simulator_handshake", Canonical().Add("handshake", in.handshake).Digest());
  }
  if (in.config->low_fidelity) {
    parts.emplace_back("low_fidelity", LowFidelityPart(*in.config, in.low_fidelity_handshake));
  }
  parts.emplace_back("version", Canonical().Add("combabc", in.version).Digest());
  Canonical combined;
  for (const auto& [part, digest] : parts) combined.Add(part.c_str(), digest);
  parts.emplace_back("combined", combined.Digest());
  return parts;
}

namespace {

// The parts stored with the run that differ from `now`, in the order the run stored them.
std::vector<std::string> ChangedParts(const Fingerprint& stored, const Fingerprint& now) {
  const std::map<std::string, std::string> current(now.begin(), now.end());
  const std::map<std::string, std::string> before(stored.begin(), stored.end());
  std::vector<std::string> changed;
  // A part the run has and this problem lacks, or the other way round, is a change of simulator
  // kind (e.g. a worker run resumed as a sensor run): reported as the simulator.
  for (const char* part : {"simulator_outputs", "simulator_handshake"}) {
    if (!before.empty() && before.count(part) != current.count(part) &&
        before.count("simulator") != 0) {
      changed.emplace_back("simulator");
      break;
    }
  }
  // A cheap simulator added to a single-fidelity run or taken from a multi-fidelity one.
  if (!before.empty() && before.count("low_fidelity") != current.count("low_fidelity") &&
      (before.count("simulator") != 0 || before.count("python_problem") != 0)) {
    changed.emplace_back("low_fidelity");
  }
  for (const auto& [part, digest] : stored) {
    const auto found = current.find(part);
    // "combined" only summarises the others; a part this combabc does not compute cannot be
    // compared (and a newer combabc's file has a newer schema, refused on open).
    if (part == "combined" || found == current.end()) continue;
    if (found->second != digest &&
        std::find(changed.begin(), changed.end(), part) == changed.end()) {
      changed.push_back(part);
    }
  }
  return changed;
}

}  // namespace

Fingerprint ComputeProblemFingerprint(const ProblemFingerprintInputs& in) {
  // The stop limits as a default SmcOptions has them: a resume may change them.
  SmcOptions sampled = *in.options;
  const SmcOptions defaults;
  sampled.max_simulations = defaults.max_simulations;
  sampled.min_acceptance_rate = defaults.min_acceptance_rate;
  sampled.max_failure_fraction = defaults.max_failure_fraction;
  Canonical sampler;
  sampler.Add("sampler", SamplerPart(sampled))
      .Add("batch_size", static_cast<long long>(in.options->batch_size));
  Canonical data;
  data.Add("values", in.observed);
  if (!in.positions.empty()) data.Add("positions", in.positions);
  Canonical metric;
  for (const DistanceComponent& d : in.components) {
    metric.Add("component", d.name)
        .Add("kind", static_cast<int>(d.kind))
        .Add("required", d.required);
  }
  Canonical calling;
  calling.Add("simulator", "python");
  for (const auto& [key, value] : in.calling) calling.Add(key.c_str(), value);
  Fingerprint parts = {{"sampler", sampler.Digest()},
                       {"space", SpacePart(*in.space)},
                       {"data", data.Digest()},
                       {"metric", metric.Digest()},
                       {"python_problem", calling.Digest()}};
  if (in.low_fidelity) {
    const MultiFidelityOptions& mf = in.options->multi_fidelity;
    Canonical low;
    low.Add("continue_if_accepted", mf.continue_if_accepted)
        .Add("continue_if_rejected", mf.continue_if_rejected)
        .Add("adapt", mf.adapt)
        .Add("floor", mf.floor)
        .Add("cost_ratio", mf.cost_ratio);
    parts.emplace_back("low_fidelity", low.Digest());
  }
  parts.emplace_back("version", Canonical().Add("combabc", in.version).Digest());
  Canonical combined;
  for (const auto& [part, digest] : parts) combined.Add(part.c_str(), digest);
  parts.emplace_back("combined", combined.Digest());
  return parts;
}

void CheckProblemFingerprint(const Fingerprint& stored,
                             const Fingerprint& now,
                             const std::string& history_path,
                             const std::string& stored_version,
                             const std::string& version) {
  const bool older = std::any_of(stored.begin(), stored.end(), [](const auto& part) {
    return part.first == "python_options";
  });
  if (older) {
    // Fingerprinted before a problem's run had the parts above (combabc before 2026-12).
    throw Error(ErrorKind::kUsage,
                "the run was written by an older combabc (" + stored_version +
                    ") whose fingerprint this one does not compute; resume it with that combabc "
                    "or start a new run",
                history_path);
  }
  const std::vector<std::string> changed = ChangedParts(stored, now);
  if (changed.empty()) return;
  const auto has = [&](const char* part) {
    return std::find(changed.begin(), changed.end(), part) != changed.end();
  };
  const bool problem = std::any_of(changed.begin(), changed.end(), [](const std::string& part) {
    return part != "sampler" && part != "version";
  });
  if (!problem && !has("sampler")) {
    throw Error(ErrorKind::kUsage,
                "this combabc (" + version + ") is not the one that started the run (" +
                    stored_version + "): fingerprint_version differs; resume with combabc " +
                    stored_version + " or start a new run",
                history_path);
  }
  throw Error(ErrorKind::kUsage,
              std::string(problem ? "the problem (space, reals, data, distance)" : "the options") +
                  " differ from the run's: resume it with the problem and options it started "
                  "with (threads and stop limits may change)",
              history_path);
}

bool SameFingerprint(Fingerprint a, Fingerprint b) {
  std::sort(a.begin(), a.end());
  std::sort(b.begin(), b.end());
  return a == b;
}

std::optional<CalibrationConfig> LegacyReading(
    const CalibrationConfig& config,
    const Fingerprint& now,
    const Fingerprint& stored,
    const std::function<Fingerprint(const CalibrationConfig&)>& fingerprint_of) {
  if (config.simulator.kind != SimulatorKind::kSensor ||
      config.model.theory != plate::PlateTheory::kRzt || SameFingerprint(now, stored)) {
    return std::nullopt;
  }
  CalibrationConfig kirchhoff = config;
  kirchhoff.model.theory = plate::PlateTheory::kKirchhoff;
  if (!SameFingerprint(fingerprint_of(kirchhoff), stored)) return std::nullopt;
  return kirchhoff;
}

void CheckResumeFingerprint(const Fingerprint& stored,
                            const Fingerprint& now,
                            const std::string& history_path,
                            const std::string& data_source,
                            const std::string& stored_version,
                            const std::string& version,
                            const std::string& handshake) {
  const std::vector<std::string> changed = ChangedParts(stored, now);
  if (changed.empty()) return;
  const std::string& part = changed.front();
  const std::string key = "fingerprint_" + part;
  std::string message;
  if (part == "data") {
    message = "the measured data changed since the run started (" + data_source + ": " + key +
              " differs); start a new run or restore the file";
  } else if (part == "simulator_handshake") {
    message = "the worker's handshake is now " + Excerpt(handshake) +
              ", not the one the run started with (" + key +
              " differs): the worker program changed; restore it or start a new run";
  } else if (part == "version") {
    message = "this combabc (" + version + ") is not the one that started the run (" +
              stored_version + "): " + key + " differs; resume with combabc " + stored_version +
              " or start a new run";
  } else {
    const std::map<std::string, std::string> what = {
        {"sampler", "the sampler options ([sampler], [sampler.moves], [proposal])"},
        {"space", "the parameter space (bits, priors, ties, continuous parameters)"},
        {"metric", "the metric ([metric])"},
        {"simulator",
         "the simulator (its kind, and [model] for the sensor or the program, argv, hand-over, "
         "timeout and retries in [simulator])"},
        {"simulator_outputs", "the simulator's declared outputs ([simulator.outputs])"},
        {"low_fidelity",
         "the multi-fidelity set-up (the cheap simulator of [simulator.low_fidelity], whether "
         "there "
         "is one, and [sampler.multi_fidelity])"},
    };
    const auto named = what.find(part);
    message = (named != what.end() ? named->second : "the run's " + part) +
              " as this combabc reads the run's configuration differ from when the run started (" +
              key + " differs); start a new run";
  }
  for (std::size_t i = 1; i < changed.size(); ++i) {
    message += (i == 1 ? " (also fingerprint_" : ", fingerprint_") + changed[i];
    if (i + 1 == changed.size()) message += ")";
  }
  throw Error(ErrorKind::kConfig, "resume: " + message, history_path);
}

}  // namespace combabc::services
