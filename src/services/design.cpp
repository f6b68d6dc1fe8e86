#include "combabc/services/design.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>

#include "combabc/config/config.hpp"
#include "combabc/core/error.hpp"
#include "combabc/core/output_files.hpp"
#include "combabc/core/thread_pool.hpp"
#include "combabc/history/history_store.hpp"
#include "combabc/params/binary_space.hpp"
#include "combabc/plate/assembly/plate.hpp"
#include "combabc/plate/sensor_model.hpp"
#include "combabc/rng/random_stream.hpp"
#include "services/python_script.hpp"

namespace combabc::services {
namespace fs = std::filesystem;
namespace {

constexpr std::uint64_t kPriorStream = 0xD4'0000'0000ULL;

std::string DesignNumber(double x) {
  char b[40];
  std::snprintf(b, sizeof b, "%.6g", x);
  return b;
}

// Adds `bits` with weight w, merging repeats: a posterior holds many copies of a configuration,
// and each distinct one is simulated once.
void AddDesignParticle(std::map<std::vector<std::uint8_t>, double>& merged,
                       std::vector<std::uint8_t> bits,
                       double w) {
  merged[std::move(bits)] += w;
}

design::Population ToPopulation(const std::map<std::vector<std::uint8_t>, double>& merged,
                                int dimension) {
  design::Population p;
  p.dimension = dimension;
  double total = 0.0;
  for (const auto& [bits, w] : merged) total += w;
  for (const auto& [bits, w] : merged) {
    p.bits.insert(p.bits.end(), bits.begin(), bits.end());
    p.weights.push_back(w / total);
  }
  return p;
}

design::Population FromPosterior(const std::string& path,
                                 const CalibrationConfig& c,
                                 std::string* what) {
  const HistoryStore store = HistoryStore::Open(path, true);
  const RunMetadata m = store.LoadMetadata();
  if (m.dimension != c.space.dimension) {
    throw Error(ErrorKind::kUsage,
                "the run has " + std::to_string(m.dimension) + " bits; the config's model has " +
                    std::to_string(c.space.dimension),
                path,
                0,
                "--posterior");
  }
  const RunHistory h = store.LoadHistory();
  const WaveRecord* last = nullptr;
  for (const WaveRecord& w : h.waves) {
    if (w.complete) last = &w;
  }
  if (last == nullptr || last->particles.empty()) {
    throw Error(
        ErrorKind::kUsage, "the run has no complete wave to start from", path, 0, "--posterior");
  }
  // A multi-fidelity run's signed weights are no distribution to draw truths from and weigh
  // candidates by (a configuration's merged weight may be negative): refused, with what to do.
  if (std::any_of(last->particles.begin(), last->particles.end(), [](const Particle& p) {
        return p.weight < 0.0 || p.multiplier < 0.0;
      })) {
    throw Error(ErrorKind::kUsage,
                "wave " + std::to_string(last->wave + 1) +
                    " of the run has negative (multi-fidelity) weights, which cannot be a design's "
                    "population: design from the prior (leave out --posterior) or from a "
                    "single-fidelity run",
                path,
                0,
                "--posterior");
  }
  std::map<std::vector<std::uint8_t>, double> merged;
  double total = 0.0;
  for (const Particle& p : last->particles) total += p.weight;
  for (const Particle& p : last->particles) {
    // The paper's estimator counts accepted particles; importance weights otherwise.
    const double w = m.estimator == "paper" || !(total > 0.0) ? 1.0 : p.weight;
    AddDesignParticle(merged, p.theta.bits, w);
  }
  *what = "the posterior of " + path + " (wave " + std::to_string(last->wave + 1) + ", " +
          std::to_string(last->particles.size()) + " particles, " + std::to_string(merged.size()) +
          " distinct)";
  return ToPopulation(merged, m.dimension);
}

design::Population FromPrior(const CalibrationConfig& c, std::string* what) {
  const BinarySpace space(c.space);
  const int free = space.num_free();
  const std::vector<double>& prior = space.free_prior_one();
  std::map<std::vector<std::uint8_t>, double> merged;
  std::vector<std::uint8_t> f(static_cast<std::size_t>(free));
  std::vector<std::uint8_t> bits(static_cast<std::size_t>(space.dimension()));
  if (free <= kDesignExactBits) {
    for (std::uint64_t code = 0; code < (std::uint64_t{1} << free); ++code) {
      double mass = 1.0;
      for (int k = 0; k < free; ++k) {
        f[static_cast<std::size_t>(k)] = (code >> k) & 1U;
        mass *= f[static_cast<std::size_t>(k)] ? prior[k] : 1.0 - prior[k];
      }
      space.Expand(f, bits);
      AddDesignParticle(merged, bits, mass);
    }
    *what = "the prior (every one of " + std::to_string(merged.size()) + " configurations)";
    return ToPopulation(merged, space.dimension());
  }
  const int n = c.design->particles;
  for (int i = 0; i < n; ++i) {
    RandomStream rng(c.smc.seed, kPriorStream, static_cast<std::uint64_t>(i));
    for (int k = 0; k < free; ++k) f[static_cast<std::size_t>(k)] = rng.Uniform() < prior[k];
    space.Expand(f, bits);
    AddDesignParticle(merged, bits, 1.0);
  }
  *what =
      "the prior (" + std::to_string(n) + " draws, " + std::to_string(merged.size()) + " distinct)";
  return ToPopulation(merged, space.dimension());
}

std::vector<DesignCandidate> Candidates(const DesignConfig& d) {
  std::vector<DesignCandidate> out;
  for (double x : d.load_x) {
    for (double y : d.load_y_fraction) {
      for (const auto& [from, to] : d.scans) {
        for (double line : d.scan_y_fraction) out.push_back({x, y, from, to, line});
      }
    }
  }
  return out;
}

std::vector<double> ScanPositions(const DesignCandidate& c, double spacing) {
  return DesignScanPositions(c.scan_from, c.scan_to, spacing);
}

// Each candidate's normalised profile for every particle: one plate model whose load cases are
// the candidates, solved once per particle (one factorization for all of them). A configuration
// the plate cannot be solved in (plate::SingularSystem: a rigid-body motion left free) is
// dropped from `population` with its weight, as a run fails that candidate; its count and reason
// go to `o`. Only when every configuration is singular is the design refused.
std::vector<design::CandidateProfiles> SimulateCandidates(const CalibrationConfig& c,
                                                          design::Population& population,
                                                          int threads,
                                                          DesignOutcome& o) {
  const plate::SensorOptions options = DesignSensorOptions(c);
  ThreadPool pool(threads);
  plate::PrecomputeOptions precompute;
  precompute.pool = &pool;
  precompute.cache_directory = plate::DefaultPrecomputeCache();
  const plate::SensorModel model(options, precompute);
  const std::size_t n = population.size();
  const auto d = static_cast<std::size_t>(population.dimension);
  const auto outputs = static_cast<std::size_t>(model.num_outputs());
  std::vector<double> all(n * outputs);
  std::vector<std::string> singular(n);  // the reason, for each singular configuration
  // Each configuration writes only its own row, so the result does not depend on the schedule.
  pool.ParallelFor(n, 16, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      try {
        model.Profile(std::span(population.bits).subspan(i * d, d),
                      std::span(all).subspan(i * outputs, outputs));
      } catch (const plate::SingularSystem& e) {
        singular[i] = e.message();
      }
    }
  });
  std::vector<std::size_t> kept;
  for (std::size_t i = 0; i < n; ++i) {
    if (singular[i].empty()) {
      kept.push_back(i);
    } else {
      if (o.singular == 0) o.singular_reason = singular[i];
      ++o.singular;
    }
  }
  if (kept.empty()) {
    throw Error(ErrorKind::kConfig,
                "every one of the " + std::to_string(n) +
                    " configurations to design from is singular: " + singular.front(),
                c.path,
                c.design->line,
                "design");
  }
  if (kept.size() < n) {
    design::Population p;
    p.dimension = population.dimension;
    double total = 0.0;
    for (std::size_t i : kept) total += population.weights[i];
    for (std::size_t i : kept) {
      p.bits.insert(p.bits.end(),
                    population.bits.begin() + static_cast<std::ptrdiff_t>(i * d),
                    population.bits.begin() + static_cast<std::ptrdiff_t>(i * d + d));
      p.weights.push_back(population.weights[i] / total);
    }
    population = std::move(p);
  }
  const std::size_t candidates = options.load_cases.size();
  std::vector<design::CandidateProfiles> profiles(candidates);
  for (std::size_t k = 0; k < candidates; ++k) {
    const std::size_t begin = options.OutputOffset(k);
    const std::size_t points = options.load_cases[k].output_positions.size();
    profiles[k].points = static_cast<int>(points);
    profiles[k].values.resize(kept.size() * points);
    for (std::size_t r = 0; r < kept.size(); ++r) {
      std::copy_n(all.begin() + static_cast<std::ptrdiff_t>(kept[r] * outputs + begin),
                  points,
                  profiles[k].values.begin() + static_cast<std::ptrdiff_t>(r * points));
    }
  }
  return profiles;
}

std::string ExperimentBlock(const DesignCandidate& k, const CalibrationConfig& c, int rank) {
  std::ostringstream out;
  out << "# The best next experiment by `combabc design` (rank " << rank
      << "): add it to the config's [[experiment]] tables once measured.\n"
      << "[[experiment]]\nname = \"x" << DesignNumber(k.load_x * 100) << "cm"
      << (k.load_y_fraction != 0.5 ? "_y" + DesignNumber(k.load_y_fraction) : "") << "\"\n"
      << "[experiment.load]\nx = " << DesignNumber(k.load_x) << "                # m\n"
      << "y_fraction = " << DesignNumber(k.load_y_fraction) << "\n"
      << "amplitude = " << DesignNumber(c.model.load_cases.front().load_force) << "          # N\n"
      << "frequency = " << DesignNumber(c.model.frequency_hz) << "            # Hz\n"
      << "[experiment.output]\npositions = [";
  const std::vector<double> x = ScanPositions(k, c.design->scan_spacing);
  for (std::size_t i = 0; i < x.size(); ++i) out << (i ? ", " : "") << DesignNumber(x[i]);
  out << "]  # m\ny_fraction = " << DesignNumber(k.scan_y_fraction) << "\n"
      << "[experiment.data]\ncsv = \"FILL IN: the measured profile\"\n"
      << "position_unit = \"cm\"\nwindow = [" << DesignNumber(k.scan_from * 100) << ", "
      << DesignNumber(k.scan_to * 100) << "]  # cm\n"
      << "[experiment.metric]\n[[experiment.metric.component]]\ntype = \"least_squares\"\n"
      << "window = [" << DesignNumber(k.scan_from * 100) << ", " << DesignNumber(k.scan_to * 100)
      << "]  # cm\n"
      << "noise = \"gaussian\"\nsigma_noise = " << DesignNumber(c.design->noise) << "\n";
  return out.str();
}

void WriteFiles(OutputDirectory& dir, const DesignOutcome& o, const CalibrationConfig& c) {
  const design::DesignResult& r = o.result;
  std::vector<std::size_t> order(o.candidates.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return r.scores[a].information_gain > r.scores[b].information_gain;
  });
  std::ostream& table = dir.Add("design.csv");
  table << "rank,candidate,load_x_m,load_y_fraction,scan_from_m,scan_to_m,scan_y_fraction,"
           "information_gain_bits,information_gain_se,expected_identified,expected_wrong,"
           "effective_particles\n";
  for (std::size_t rank = 0; rank < order.size(); ++rank) {
    const std::size_t k = order[rank];
    const DesignCandidate& d = o.candidates[k];
    const design::Score& s = r.scores[k];
    table << rank + 1 << ',' << k + 1 << ',' << DesignNumber(d.load_x) << ','
          << DesignNumber(d.load_y_fraction) << ',' << DesignNumber(d.scan_from) << ','
          << DesignNumber(d.scan_to) << ',' << DesignNumber(d.scan_y_fraction) << ','
          << DesignNumber(s.information_gain) << ',' << DesignNumber(s.information_gain_se) << ','
          << DesignNumber(s.identified) << ',' << DesignNumber(s.wrong) << ','
          << DesignNumber(s.effective_particles) << '\n';
  }
  std::ostream& selection = dir.Add("selection.csv");
  selection << "step,candidate,load_x_m,load_y_fraction,scan_from_m,scan_to_m,scan_y_fraction,"
               "information_gain_bits,information_gain_se,expected_identified,expected_wrong,"
               "effective_particles\n";
  for (std::size_t step = 0; step < r.selected.size(); ++step) {
    const auto k = static_cast<std::size_t>(r.selected[step]);
    const DesignCandidate& d = o.candidates[k];
    const design::Score& s = r.cumulative[step];
    selection << step + 1 << ',' << k + 1 << ',' << DesignNumber(d.load_x) << ','
              << DesignNumber(d.load_y_fraction) << ',' << DesignNumber(d.scan_from) << ','
              << DesignNumber(d.scan_to) << ',' << DesignNumber(d.scan_y_fraction) << ','
              << DesignNumber(s.information_gain) << ',' << DesignNumber(s.information_gain_se)
              << ',' << DesignNumber(s.identified) << ',' << DesignNumber(s.wrong) << ','
              << DesignNumber(s.effective_particles) << '\n';
  }
  std::ostream& ident = dir.Add("identifiability.csv");
  ident << "candidate,label";
  for (const std::string& name : c.space.names) ident << ',' << '"' << name << '"';
  ident << '\n';
  for (std::size_t k = 0; k < o.candidates.size(); ++k) {
    const DesignCandidate& d = o.candidates[k];
    ident << k + 1 << ",\"load " << DesignNumber(d.load_x * 100) << " cm, y "
          << DesignNumber(d.load_y_fraction) << "; scan " << DesignNumber(d.scan_from * 100) << "-"
          << DesignNumber(d.scan_to * 100) << " cm, y " << DesignNumber(d.scan_y_fraction) << "\"";
    for (double v : r.scores[k].identifiability) ident << ',' << DesignNumber(v);
    ident << '\n';
  }
  dir.Add("next_experiment.toml") << o.next_experiment;
}

}  // namespace

DesignOutcome RunDesign(const DesignRequest& request) {
  const auto start = std::chrono::steady_clock::now();
  CalibrationConfig c = LoadConfig(request.config_path);
  if (!c.design) {
    throw Error(ErrorKind::kConfig,
                "missing required table [design] (the candidate experiments to rank; "
                "docs/config.md, \"Design\")",
                c.path,
                1,
                "design");
  }
  if (c.simulator.kind != SimulatorKind::kSensor) {
    throw Error(ErrorKind::kUsage,
                "design simulates the built-in sensor's candidate loads and scans; this config's "
                "simulator is " +
                    std::string(ToString(c.simulator.kind)),
                c.path);
  }
  // A cheap simulator ([simulator.low_fidelity]) is not used: design simulates [model]'s sensor
  // (docs/config.md, "Multi-fidelity").
  if (!c.reals.empty()) {
    throw Error(ErrorKind::kUsage,
                "design ranks experiments by what they tell about the bits; remove [parameters] "
                "(the continuous unknowns) or fix them at nominal values",
                c.path);
  }
  const int threads = request.threads >= 0 ? request.threads : c.smc.threads;
  const std::string directory =
      request.output_directory.empty()
          ? (fs::path(ResolvePath(c.directory, c.output.directory)) / "design").string()
          : request.output_directory;
  // Refused now rather than after the simulations; the parent folder is made only at the end.
  const fs::path parent = fs::path(directory).parent_path();
  std::error_code ec;
  if (parent.empty() || fs::exists(parent, ec)) {
    OutputDirectory::Check(directory, request.overwrite);
  }

  DesignOutcome o;
  design::Population population = request.posterior_path.empty()
                                      ? FromPrior(c, &o.population)
                                      : FromPosterior(request.posterior_path, c, &o.population);
  if (!request.posterior_path.empty()) {
    // The prior's population was sized against memory_limit_gb when the config was read; a
    // posterior's is known only now.
    const DesignMemory memory = EstimateDesignMemory(c, static_cast<double>(population.size()));
    if (memory.total() > c.model.memory_limit_bytes) {
      throw Error(ErrorKind::kUsage,
                  "its " + std::to_string(population.size()) +
                      " distinct configurations would need about " +
                      DesignNumber(memory.total() / 1e9) + " GB of memory to design from (limit " +
                      DesignNumber(c.model.memory_limit_bytes / 1e9) +
                      " GB); fewer truths or scan points in [design], or raise memory_limit_gb",
                  request.posterior_path,
                  0,
                  "--posterior");
    }
  }
  o.exhaustive =
      request.posterior_path.empty() && BinarySpace(c.space).num_free() <= kDesignExactBits;
  o.candidates = Candidates(*c.design);
  const std::vector<design::CandidateProfiles> profiles =
      SimulateCandidates(c, population, threads, o);
  o.particles = population.size();
  design::DesignOptions options;
  options.noise_sigma = c.design->noise;
  o.noise_sigma = options.noise_sigma;
  options.truths = c.design->truths;
  options.select = c.design->select;
  options.identified_margin = c.design->identified_margin;
  options.seed = c.smc.seed;
  options.threads = threads;
  o.result = design::ScoreCandidates(population, profiles, options);
  o.next_experiment =
      ExperimentBlock(o.candidates[static_cast<std::size_t>(o.result.selected.front())], c, 1);

  if (!parent.empty() && !fs::exists(parent, ec)) {
    fs::create_directories(parent, ec);
    if (ec) {
      throw Error(
          ErrorKind::kCantCreate, "cannot create directory: " + ec.message(), parent.string());
    }
  }
  OutputDirectory dir(directory, request.overwrite);
  WriteFiles(dir, o, c);
  if (request.figure) {
    const PythonScript script = FindPythonScript(
        "combabc_design.py", "COMBABC_DESIGN_SCRIPT", "python3-numpy and python3-matplotlib");
    for (const std::string& format : c.output.figure_formats) {
      const std::string name = "identifiability." + format;
      dir.Add(name);
      const ProcessResult result = RunProcess({script.python,
                                               script.script,
                                               dir.StagedPath("identifiability.csv"),
                                               dir.StagedPath(name),
                                               format},
                                              "python3-numpy and python3-matplotlib");
      if (result.status != 0) {
        throw Error(KindOfScriptStatus(result.status),
                    name + ": " + ScriptMessage(result.err, result.status, "combabc_design"));
      }
    }
  }
  dir.Commit();
  o.directory = directory;
  o.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return o;
}

}  // namespace combabc::services
