#include "combabc/config/config.hpp"

#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <sstream>
#include <thread>

#include "combabc/core/bounded_read.hpp"
#include "combabc/core/error.hpp"
#include "combabc/core/validation_error.hpp"
#include "combabc/params/binary_space.hpp"
#include "combabc/samplers/multi_fidelity.hpp"
#include "combabc/samplers/run_history.hpp"
#include "config_model_choice.hpp"
#include "config_reader.hpp"

namespace combabc {
namespace {

using config_internal::OneOf;
using config_internal::Source;
using config_internal::Sources;
using config_internal::TableReader;

// --------------------------------------------------------------------------------------- output
void ParseOutput(TableReader& root, CalibrationConfig* c) {
  auto t = root.Table("output");
  if (!t) return;
  OutputConfig& o = c->output;
  o.directory = t->String("directory").value_or(o.directory);
  if (o.directory.empty()) t->Fail("directory", "must not be empty");
  o.database = t->String("database").value_or(o.database);
  if (o.database.empty() || o.database.find('/') != std::string::npos || o.database == "." ||
      o.database == "..") {
    t->Fail("database", "must be a file name (it is created inside output.directory)");
  }
  // The folders a run writes beside its history (services: report/, export/, and from the
  // history's stem <stem>.work/ for an external simulator, <stem>.enumeration/ for enumerate), and
  // enumerate's own folder: a history of one of their names would be found to collide only after
  // sampling.
  const std::string stem = std::filesystem::path(o.database).stem().string();
  for (const std::string& folder : {std::string("report"),
                                    std::string("export"),
                                    stem + ".work",
                                    stem + ".enumeration",
                                    std::string(kEnumerationFolder)}) {
    if (o.database == folder) {
      t->Fail("database",
              Excerpt(o.database) + " is the name of the folder the run writes beside its " +
                  "history (" + folder + "/); choose another file name, e.g. history.sqlite");
    }
  }
  if (const auto formats = t->Strings("figures")) {
    for (const std::string& f : *formats) {
      if (f != "png" && f != "svg" && f != "pdf") {
        t->Fail(
            "figures",
            "unknown figure format " + Excerpt(f) + "; expected " + OneOf({"png", "svg", "pdf"}));
      }
    }
    o.figure_formats = *formats;
  }
  o.keep_simulated_curves = t->Bool("keep_simulated_curves").value_or(o.keep_simulated_curves);
  t->Finish();
}

// The config key of an SmcOptions / BinarySpaceOptions field the user did not set.
std::string SamplerKeyOf(const std::string& field) {
  static const std::map<std::string, std::string> keys = {
      {"num_waves", "sampler.waves"},
      {"accepted_per_wave", "sampler.accepted_per_wave"},
      {"threads", "sampler.threads"},
      {"max_simulations", "sampler.max_simulations"},
      {"min_acceptance_rate", "sampler.min_acceptance_rate"},
      {"acceptance_floor_after", "sampler.acceptance_floor_after"},
      {"max_failure_fraction", "sampler.max_failure_fraction"},
      {"failure_fraction_after", "sampler.failure_fraction_after"},
      {"max_wall_time_s", "sampler.max_wall_time"},
      {"batch_size", "sampler.batch_size"},
      {"tempering", "sampler.tempering"},
      {"multi_fidelity", "sampler.multi_fidelity"},
      {"moves", "sampler.moves"},
      {"method", "sampler.method"},
      {"thresholds", "metric"},
      {"default_prior_one", "sampler.prior"},
      {"prior_one", "sampler.prior"},
      {"tied", "sampler.tie"},
  };
  const auto it = keys.find(field);
  return it != keys.end() ? it->second : "sampler";
}

// Reports a failed SmcOptions / BinarySpaceOptions check at the config key that set its field, in
// the config's words, so C++ field names never reach the user ("sampler.waves: is 0; must be >=
// 1"): the key of the member the field lies in ("tempering" of "tempering.values"), and below it
// the rest of the field ("values has 1 entries; ...", "[0] has zero prior mass: ...").
[[noreturn]] void ThrowAttributed(const ValidationError& error,
                                  const std::map<std::string, Source>& map,
                                  const Source& fallback,
                                  const std::string& path) {
  const std::size_t dot = error.field.find('.');
  const std::string member = error.field.substr(0, dot);  // "tied[0]", "proposal"
  const std::string below = dot == std::string::npos ? "" : error.field.substr(dot + 1);
  const std::string base = member.substr(0, member.find('['));  // "tied"
  auto it = map.find(member);
  if (it == map.end()) it = map.find(base);
  const bool set_by_user = it != map.end();
  const std::string key = set_by_user ? it->second.key : SamplerKeyOf(base);
  const int line = set_by_user ? it->second.line : fallback.line;
  std::string detail;
  if (below.empty() && !error.value.empty()) {
    detail = "is " + error.value + "; " + error.constraint;
  } else {
    detail = below.empty() ? error.constraint
                           : ValidationError{"", below, error.value, error.constraint}.Detail();
    if (member != base) detail = member.substr(base.size()) + " " + detail;
  }
  throw Error(ErrorKind::kConfig, detail, path, line, key);
}

// The sampler's share of memory (bytes): the candidate batch's buffers and, for every wave, its
// accepted particles (bits, distances, and outputs when kept) and pair correlations (d x d), which
// the run keeps until it ends.
struct SamplerMemory {
  double batch = 0.0;
  double particles = 0.0;
};

// The largest batch the automatic batch size can choose (CombinatorialSmc's BatchSize): 4096
// candidates, or 32 per worker on more than 128 threads; threads = 0 is all of this machine's
// cores.
double AutomaticBatchBound(const CalibrationConfig& c) {
  const unsigned cores = std::max(1U, std::thread::hardware_concurrency());
  const double threads = c.smc.threads > 0 ? c.smc.threads : cores;
  return std::max(4096.0, 32.0 * threads);
}

// The particles the run keeps over all waves, and the most of any wave.
double TotalAccepted(const SmcOptions& smc) {
  double total = 0.0;
  for (int t = 0; t < smc.num_waves; ++t) total += smc.AcceptedIn(t);
  return total;
}
int MostAccepted(const SmcOptions& smc) {
  int most = 0;
  for (int t = 0; t < smc.num_waves; ++t) most = std::max(most, smc.AcceptedIn(t));
  return most;
}

SamplerMemory EstimateSamplerMemory(const CalibrationConfig& c) {
  const auto d = static_cast<double>(c.space.dimension);
  const auto m = static_cast<double>(c.simulator.outputs.size());
  double components = 0.0;
  for (const ExperimentConfig& x : c.experiments) {
    components += static_cast<double>(x.metric.components.size());
  }
  constexpr double kOverheadBytes = 160.0;  // vector headers, allocator slack, RNG state
  const double batch = c.smc.batch_size > 0 ? c.smc.batch_size : AutomaticBatchBound(c);
  SamplerMemory memory;
  memory.batch = batch * (2.0 * d + 8.0 * (m + components) + kOverheadBytes);
  // A multi-fidelity wave keeps up to kMultiFidelityParticlesPerAccepted particles per one it
  // needs (the engine stops it there), each with its cheap distances as well.
  const bool multi_fidelity = c.low_fidelity.has_value();
  const double kept = multi_fidelity ? kMultiFidelityParticlesPerAccepted : 1.0;
  const double cheap = multi_fidelity ? 8.0 * components + 32.0 : 0.0;
  memory.particles =
      kept * TotalAccepted(c.smc) *
          (d + 8.0 * components + cheap + (c.smc.keep_outputs ? 8.0 * m : 0.0) + kOverheadBytes) +
      (d <= static_cast<double>(kMaxPairCorrelationBits)
           ? static_cast<double>(c.smc.num_waves) * 8.0 * d * d
           : 0.0);
  return memory;
}

std::string Gigabytes(double bytes) {
  std::ostringstream os;
  os.precision(bytes < 1e8 ? 2 : 3);
  os << bytes / 1e9 << " GB";
  return os.str();
}

// The model's precompute and the sampler's buffers together must fit memory_limit_gb; blamed on
// the sampler key that asks for the larger share.
void CheckRunMemory(const CalibrationConfig& c, const Sources& sources) {
  // An external simulator's memory is its own processes', not combabc's.
  const bool sensor = c.simulator.kind == SimulatorKind::kSensor;
  double model = 0.0;
  if (sensor) {
    bool loss_factor_unknown = false;
    for (const ContinuousParameter& r : c.reals) loss_factor_unknown |= r.name == "loss_factor";
    for (const SensorModelPlan& plan : SensorModels(c)) {
      model += plan.options.EstimatedMemoryBytes();
      // A mixed run also builds the continuous-unknowns precompute (on its first simulation).
      if (!c.reals.empty()) {
        model += plan.options.EstimatedContinuousMemoryBytes(loss_factor_unknown);
      }
    }
  }
  // A cheap sensor of a multi-fidelity run is built beside the run's simulator.
  if (c.low_fidelity && c.low_fidelity->simulator.kind == SimulatorKind::kSensor) {
    for (const SensorModelPlan& plan : LowFidelitySensorModels(c)) {
      model += plan.options.EstimatedMemoryBytes();
    }
  }
  const SamplerMemory sampler = EstimateSamplerMemory(c);
  const double total = model + sampler.batch + sampler.particles;
  if (total <= c.model.memory_limit_bytes) return;
  std::string field = sampler.batch > sampler.particles ? "batch_size" : "accepted_per_wave";
  if (field == "accepted_per_wave" && sources.smc.count("num_waves") &&
      c.smc.num_waves > MostAccepted(c.smc)) {
    field = "num_waves";
  }
  const auto it = sources.smc.find(field);
  const Source source = it != sources.smc.end() ? it->second : sources.sampler;
  const double value = field == "batch_size"  ? c.smc.batch_size
                       : field == "num_waves" ? c.smc.num_waves
                                              : MostAccepted(c.smc);
  // batch_size = 0 is the automatic size: "lower it" would mean nothing there.
  const bool automatic = field == "batch_size" && c.smc.batch_size == 0;
  const std::string advice =
      automatic ? "; set a smaller batch_size or fewer threads, or raise memory_limit_gb"
                : "; lower it or raise memory_limit_gb";
  throw Error(ErrorKind::kConfig,
              "is " + std::to_string(static_cast<long long>(value)) +
                  (automatic ? " (automatic: up to " +
                                   std::to_string(static_cast<long long>(AutomaticBatchBound(c))) +
                                   " candidates a batch)"
                             : "") +
                  "; the run would need about " + Gigabytes(total) + " of memory (limit " +
                  Gigabytes(c.model.memory_limit_bytes) + "): model " + Gigabytes(model) +
                  ", candidate batch " + Gigabytes(sampler.batch) + ", accepted particles " +
                  Gigabytes(sampler.particles) +
                  (c.low_fidelity ? " (a multi-fidelity wave keeps up to " +
                                        std::to_string(kMultiFidelityParticlesPerAccepted) +
                                        " x accepted_per_wave)"
                                  : "") +
                  advice + " (docs/config.md, \"Limits\")",
              c.path,
              source.line,
              it != sources.smc.end() ? source.key : SamplerKeyOf(field));
}

}  // namespace

CalibrationConfig ParseConfig(std::string_view text, const std::string& path) {
  toml::table table;
  try {
    table = toml::parse(text, path);
  } catch (const toml::parse_error& e) {
    throw Error(ErrorKind::kConfig,
                "malformed TOML: " + std::string(e.description()),
                path,
                static_cast<int>(e.source().begin.line));
  }
  CalibrationConfig c = config_internal::ParseConfigTable(table, text, path);
  config_internal::BuildCandidateConfigs(&c);
  return c;
}

CalibrationConfig config_internal::ParseConfigTable(const toml::table& table,
                                                    std::string_view text,
                                                    const std::string& path) {
  CalibrationConfig c;
  c.path = path;
  c.directory = std::filesystem::path(path).parent_path().string();
  c.text = std::string(text);
  TableReader root(table, "", c.path);
  Sources sources;
  sources.sampler = {"sampler", 1};
  c.description = root.String("description").value_or("");
  std::map<std::string, Source> model_sources;
  config_internal::ParseModelSection(root, &c, &model_sources);
  config_internal::ParseSimulatorSection(root, &c);
  config_internal::ParseSamplerSection(root, &c, &sources);
  config_internal::ParseProposalSection(root, &c);
  config_internal::ParseParametersSection(root, &c);
  config_internal::ParseJointPriorSection(root, &c);
  // The default kernel (kind = "auto") as the run records it: the ancestor kernel for a mixed
  // space (a bit whose prior is neither 0 nor 1, and a real), else independent. An invalid space
  // is refused later, naming its key.
  ValidationError space_error;
  const bool uncertain = c.space.IsValid(&space_error)
                             ? AnyUncertainBit(BinarySpace(c.space).free_prior_one())
                             : c.space.dimension > 0;
  const bool auto_kernel = c.smc.proposal.binary == BinaryKernelKind::kAuto;
  c.smc.proposal = ResolvedProposal(c.smc.proposal, uncertain && !c.reals.empty());
  for (const ContinuousParameter& r : c.reals) c.simulator.external.real_names.push_back(r.name);
  if (c.space.dimension == 0 && c.reals.empty()) {
    throw Error(ErrorKind::kConfig,
                "the simulator has no parameters to calibrate: declare bits in [simulator.bits] "
                "or continuous parameters in [parameters.<name>]",
                c.path,
                c.bits_line,
                c.bits_key);
  }
  // Sets the thresholds (one schedule per threshold or likelihood component, experiment by
  // experiment), the simulator's outputs and model.normalise.
  config_internal::ParseExperiments(root, &c, model_sources);
  config_internal::ParseLowFidelitySection(root, &c);
  if (sources.multi_fidelity && !c.low_fidelity) {
    throw Error(ErrorKind::kConfig,
                "multi-fidelity options need a cheap simulator: add [simulator.low_fidelity]",
                c.path,
                sources.multi_fidelity->line,
                sources.multi_fidelity->key);
  }
  // A move's Metropolis-Hastings step leaves one simulator's target invariant; a multi-fidelity
  // wave's weights carry the cheap simulator's continuation multipliers, which no move keeps.
  if (c.smc.method == SamplerMethod::kResampleMove && c.low_fidelity) {
    throw Error(ErrorKind::kConfig,
                "moves do not apply to multi-fidelity runs ([simulator.low_fidelity]); use "
                "method = \"rejection\" or remove the cheap simulator",
                c.path,
                sources.method->line,
                sources.method->key);
  }
  ParseOutput(root, &c);
  config_internal::ParseDesignSection(root, &c, model_sources);
  config_internal::ParseModelChoice(root, &c);
  root.Finish();
  // A joint model choice's default kernel is the ancestor kernel, bits alone or not: its defensive
  // prior proposes every model at a rate of at least 0.05 pi_k, so a model that loses its last
  // particle in one wave can come back in the next; a product kernel fitted without a floor would
  // propose it with probability 0 from then on (docs/algorithm.md, "Model choice").
  if (auto_kernel && c.model_choice && c.model_choice->joint &&
      c.smc.proposal.continuous == ContinuousKernelKind::kNormal) {
    c.smc.proposal.binary = BinaryKernelKind::kAncestor;
  }
  c.smc.keep_outputs = c.output.keep_simulated_curves;

  if (ValidationError error; !c.smc.IsValid(&error)) {
    ThrowAttributed(error, sources.smc, sources.sampler, c.path);
  }
  if (!c.reals.empty() && c.smc.estimator == Estimator::kPaper) {
    throw Error(ErrorKind::kConfig,
                "the paper estimator is unweighted; continuous parameters need importance weights "
                "(estimator = \"importance\")",
                c.path,
                sources.sampler.line,
                "sampler.estimator");
  }
  if (ValidationError error; !c.space.IsValid(&error)) {
    ThrowAttributed(error, sources.space, sources.sampler, c.path);
  }
  CheckRunMemory(c, sources);
  return c;
}

CalibrationConfig LoadConfig(const std::string& path) {
  const std::string text =
      ReadBoundedFile(path, kMaxConfigBytes, "config file", ErrorKind::kConfig);
  return ParseConfig(text, path);
}

}  // namespace combabc
