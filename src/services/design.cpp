#include "combabc/services/design.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "combabc/config/config.hpp"
#include "combabc/config/distance_from_config.hpp"
#include "combabc/core/error.hpp"
#include "combabc/core/output_files.hpp"
#include "combabc/core/thread_pool.hpp"
#include "combabc/history/history_store.hpp"
#include "combabc/params/binary_space.hpp"
#include "combabc/plate/assembly/plate.hpp"
#include "combabc/plate/sensor_model.hpp"
#include "combabc/rng/random_stream.hpp"
#include "services/adapters/python_script.hpp"
#include "services/design_campaign.hpp"

namespace combabc::services {
namespace fs = std::filesystem;
namespace {

constexpr std::uint64_t kPriorStream = 0xD4'0000'0000ULL;

double SecondsSince(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

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
                                 std::string* what,
                                 std::vector<double>* thresholds) {
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
  *thresholds = last->thresholds;
  std::map<std::vector<std::uint8_t>, double> merged;
  double total = 0.0;
  for (const Particle& p : last->particles) total += p.weight;
  for (const Particle& p : last->particles) {
    // The paper's estimator counts accepted particles; importance weights otherwise.
    const double w = m.estimator == "paper" || !(total > 0.0) ? 1.0 : p.weight;
    AddDesignParticle(merged, p.theta.bits, w);
  }
  *what = "the run " + path + " (wave " + std::to_string(last->wave + 1) + ", " +
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

// Each configuration simulated once: every candidate's normalised profile and, when asked, the
// outputs of the experiments so far as the run simulates them. The candidates are load cases of
// one plate model, with the experiments that share its frequency and normalisation (one
// factorization per configuration for all of them); other experiments have their own model.
struct Simulated {
  std::vector<design::CandidateProfiles> profiles;  // per candidate: rows x points
  std::vector<double> run;                          // rows x run_size
  std::size_t run_size = 0;
  std::vector<std::string> singular;  // per row: why the plate is singular, empty when solved
};

Simulated SimulateRows(const CalibrationConfig& c,
                       std::span<const std::uint8_t> bits,
                       std::size_t rows,
                       int threads,
                       bool experiments) {
  struct Place {
    std::size_t model = 0, load_case = 0, offset = 0;
  };
  // Without [design] (the campaign view of an export or report): no candidates, the experiments
  // only, those the candidates' model would share merged into it as usual.
  plate::SensorOptions no_candidates = c.model;
  no_candidates.normalise = true;
  no_candidates.load_cases.clear();
  std::vector<plate::SensorOptions> options{c.design ? DesignSensorOptions(c) : no_candidates};
  const std::size_t candidates = options.front().load_cases.size();
  std::vector<Place> places(c.experiments.size());
  Simulated s;
  if (experiments) {
    for (const SensorModelPlan& plan : SensorModels(c)) {
      const bool merge = plan.options.frequency_hz == options.front().frequency_hz &&
                         plan.options.normalise == options.front().normalise;
      if (!merge) options.push_back(plan.options);
      for (std::size_t i = 0; i < plan.experiments.size(); ++i) {
        Place& p = places[plan.experiments[i]];
        if (merge) {
          options.front().load_cases.push_back(plan.options.load_cases[i]);
          p = {0, options.front().load_cases.size() - 1, 0};
        } else {
          p = {options.size() - 1, i, 0};
        }
      }
    }
    for (std::size_t e = 0; e < places.size(); ++e) {
      places[e].offset = s.run_size;
      s.run_size += c.experiments[e].output_coordinates.size();
    }
  }
  ThreadPool pool(threads);
  plate::PrecomputeOptions precompute;
  precompute.pool = &pool;
  precompute.cache_directory = plate::DefaultPrecomputeCache();
  std::vector<std::unique_ptr<plate::SensorModel>> models;
  models.reserve(options.size());
  for (const plate::SensorOptions& o : options) {
    // No model for a load-case list left empty (no candidates, and no experiment merged into it).
    models.push_back(o.load_cases.empty() ? nullptr
                                          : std::make_unique<plate::SensorModel>(o, precompute));
  }
  const plate::SensorOptions& design = options.front();
  const auto d = static_cast<std::size_t>(c.space.dimension);
  s.profiles.resize(candidates);
  for (std::size_t k = 0; k < candidates; ++k) {
    s.profiles[k].points = static_cast<int>(design.load_cases[k].output_positions.size());
    s.profiles[k].values.resize(rows * static_cast<std::size_t>(s.profiles[k].points));
  }
  s.run.resize(rows * s.run_size);
  s.singular.resize(rows);
  // Each configuration writes only its own rows, so the result does not depend on the schedule.
  pool.ParallelFor(rows, 16, [&](std::size_t begin, std::size_t end) {
    std::vector<std::vector<double>> out(models.size());
    for (std::size_t m = 0; m < models.size(); ++m) {
      if (models[m]) out[m].resize(static_cast<std::size_t>(models[m]->num_outputs()));
    }
    for (std::size_t i = begin; i < end; ++i) {
      try {
        for (std::size_t m = 0; m < models.size(); ++m) {
          if (models[m]) models[m]->Profile(bits.subspan(i * d, d), out[m]);
        }
      } catch (const plate::SingularSystem& e) {
        s.singular[i] = e.message();
        continue;
      }
      for (std::size_t k = 0; k < candidates; ++k) {
        const auto points = static_cast<std::size_t>(s.profiles[k].points);
        std::copy_n(out[0].begin() + static_cast<std::ptrdiff_t>(design.OutputOffset(k)),
                    points,
                    s.profiles[k].values.begin() + static_cast<std::ptrdiff_t>(i * points));
      }
      for (std::size_t e = 0; e < places.size() && experiments; ++e) {
        const Place& p = places[e];
        const plate::SensorOptions& o = options[p.model];
        std::copy_n(out[p.model].begin() + static_cast<std::ptrdiff_t>(o.OutputOffset(p.load_case)),
                    c.experiments[e].output_coordinates.size(),
                    s.run.begin() + static_cast<std::ptrdiff_t>(i * s.run_size + p.offset));
      }
    }
  });
  return s;
}

// Each candidate's normalised profile for every particle. A configuration the plate cannot be
// solved in (plate::SingularSystem: a rigid-body motion left free) is dropped from `population`
// with its weight, as a run fails that candidate; its count and reason go to `o`. Only when every
// configuration is singular is the design refused.
std::vector<design::CandidateProfiles> SimulateCandidates(const CalibrationConfig& c,
                                                          design::Population& population,
                                                          int threads,
                                                          DesignOutcome& o) {
  const std::size_t n = population.size();
  const auto d = static_cast<std::size_t>(population.dimension);
  Simulated s = SimulateRows(c, population.bits, n, threads, false);
  std::vector<std::size_t> kept;
  for (std::size_t i = 0; i < n; ++i) {
    if (s.singular[i].empty()) {
      kept.push_back(i);
    } else {
      if (o.singular == 0) o.singular_reason = s.singular[i];
      ++o.singular;
    }
  }
  if (kept.empty()) {
    throw Error(ErrorKind::kConfig,
                "every one of the " + std::to_string(n) +
                    " configurations to design from is singular: " + s.singular.front(),
                c.path,
                c.design->line,
                "design");
  }
  if (kept.size() == n) return std::move(s.profiles);
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
  for (design::CandidateProfiles& profiles : s.profiles) {
    const auto m = static_cast<std::size_t>(profiles.points);
    std::vector<double> values(kept.size() * m);
    for (std::size_t r = 0; r < kept.size(); ++r) {
      std::copy_n(profiles.values.begin() + static_cast<std::ptrdiff_t>(kept[r] * m),
                  m,
                  values.begin() + static_cast<std::ptrdiff_t>(r * m));
    }
    profiles.values = std::move(values);
  }
  return std::move(s.profiles);
}

// The truths' neighbourhoods (design::LocalPopulation): for each distinct truth drawn from the
// run's particles, its configuration, each free parameter flipped, the swaps of the pairs a
// profile confuses most (a clamp and its mirror across the strip, a clamp and its neighbour along
// an edge) and its mirror image; log_weight holds their log prior. Rows are distinct
// configurations.
design::LocalPopulation Neighbourhoods(const CalibrationConfig& c,
                                       const design::Population& known,
                                       const std::vector<std::size_t>& truths) {
  const BinarySpace space(c.space);
  const int d = space.dimension();
  const auto free = static_cast<std::size_t>(space.num_free());
  const std::vector<double>& prior = space.free_prior_one();
  design::LocalPopulation local;
  local.dimension = d;
  for (int k = 0; k < d; ++k) local.free_of_bit.push_back(space.free_of_bit(k));
  auto flippable = [&](std::size_t f) { return prior[f] > 0.0 && prior[f] < 1.0; };
  std::set<std::pair<int, int>> pairs;
  const int n = c.model.clamps_per_edge;
  auto add = [&](int a, int b) {
    const int fa = space.free_of_bit(a), fb = space.free_of_bit(b);
    if (fa != fb) pairs.emplace(std::min(fa, fb), std::max(fa, fb));
  };
  for (int k = 0; k < n && 2 * n == d; ++k) {
    add(k, k + n);
    if (k + 1 < n) {
      add(k, k + 1);
      add(k + n, k + n + 1);
    }
  }
  std::map<std::vector<std::uint8_t>, int> row_of;
  std::vector<std::uint8_t> bits(static_cast<std::size_t>(d));
  auto row = [&](const std::vector<std::uint8_t>& f) {
    space.Expand(f, bits);
    const auto [it, fresh] = row_of.emplace(bits, static_cast<int>(row_of.size()));
    if (fresh) {
      local.bits.insert(local.bits.end(), bits.begin(), bits.end());
      double log_prior = 0.0;
      for (std::size_t k = 0; k < free; ++k) {
        log_prior += std::log(f[k] ? prior[k] : 1.0 - prior[k]);
      }
      local.log_weight.push_back(log_prior);
    }
    return it->second;
  };
  std::map<std::size_t, design::Neighbourhood> made;
  const auto width = static_cast<std::size_t>(d);
  for (std::size_t t : truths) {
    auto it = made.find(t);
    if (it == made.end()) {
      std::vector<std::uint8_t> f0(free);
      space.Reduce(std::span(known.bits).subspan(t * width, width), f0);
      design::Neighbourhood nb;
      nb.rows.push_back(row(f0));
      nb.single.assign(free, -1);
      for (std::size_t f = 0; f < free; ++f) {
        if (!flippable(f)) continue;
        std::vector<std::uint8_t> f1 = f0;
        f1[f] ^= 1U;
        nb.single[f] = static_cast<int>(nb.rows.size());
        nb.rows.push_back(row(f1));
      }
      for (const auto& [a, b] : pairs) {
        const auto fa = static_cast<std::size_t>(a), fb = static_cast<std::size_t>(b);
        if (f0[fa] == f0[fb] || !flippable(fa) || !flippable(fb)) continue;
        std::vector<std::uint8_t> f2 = f0;
        f2[fa] ^= 1U;
        f2[fb] ^= 1U;
        nb.swaps.push_back({a, b, static_cast<int>(nb.rows.size())});
        nb.rows.push_back(row(f2));
      }
      // The mirror image across the centreline (edge 1 and edge 2 exchanged): what a centreline
      // load and scan cannot tell from the truth.
      if (2 * n == d) {
        std::vector<std::uint8_t> truth(width), mirror(width), fm(free);
        space.Expand(f0, truth);
        for (std::size_t k = 0; k < width; ++k) mirror[k] = truth[(k + width / 2) % width];
        design::Neighbourhood::Group group;
        if (space.Reduce(mirror, fm) && fm != f0) {
          for (std::size_t f = 0; f < free; ++f) {
            if (fm[f] != f0[f]) group.flipped.push_back(static_cast<int>(f));
          }
          const bool possible = std::all_of(group.flipped.begin(), group.flipped.end(), [&](int f) {
            return flippable(static_cast<std::size_t>(f));
          });
          if (possible) {
            group.position = static_cast<int>(nb.rows.size());
            nb.rows.push_back(row(fm));
            nb.groups.push_back(std::move(group));
          }
        }
      }
      it = made.emplace(t, std::move(nb)).first;
    }
    local.truths.push_back(it->second);
  }
  return local;
}

// log of the run's acceptance of each row at its last complete wave: -d_k / T_k for a noise-aware
// component, 0 or -inf for a threshold (d_k <= eps_k) or indicator one; -inf for a singular row.
// The run's posterior is the prior times this (docs/algorithm.md, "Noise-aware acceptance").
// per_experiment (when given): the same, each experiment's components alone (experiments x rows).
std::vector<double> RunLogLikelihood(const CalibrationConfig& c,
                                     const Simulated& s,
                                     const std::vector<double>& thresholds,
                                     const std::string& posterior_path,
                                     std::vector<std::vector<double>>* per_experiment) {
  const std::vector<MeasuredData> data = LoadExperimentData(c);
  const std::vector<MeasuredProfile> profiles = ProfilesOf(data);
  const std::unique_ptr<JointDistance> distance = MakeDistance(c, profiles);
  const std::vector<DistanceComponent> components = distance->components();
  std::size_t threshold_count = 0;
  for (const DistanceComponent& k : components) {
    threshold_count += k.kind != ComponentKind::kIndicator;
  }
  if (threshold_count != thresholds.size()) {
    throw Error(ErrorKind::kUsage,
                "the run has " + std::to_string(thresholds.size()) +
                    " threshold components; the config's experiments have " +
                    std::to_string(threshold_count) + ": design from the run's own config",
                posterior_path,
                0,
                "--posterior");
  }
  const std::size_t rows = s.singular.size();
  constexpr double kMinusInf = -std::numeric_limits<double>::infinity();
  // The experiments' components lie one after the other in the distance (config.hpp).
  std::vector<std::size_t> experiment_of;
  for (std::size_t e = 0; e < c.experiments.size(); ++e) {
    experiment_of.insert(experiment_of.end(), c.experiments[e].metric.components.size(), e);
  }
  if (experiment_of.size() != components.size()) {
    throw Error(ErrorKind::kSoftware,
                std::to_string(components.size()) + " distance components for " +
                    std::to_string(experiment_of.size()) + " metric components",
                c.path);
  }
  std::vector<double> out(rows, kMinusInf);
  if (per_experiment != nullptr) {
    per_experiment->assign(c.experiments.size(), std::vector<double>(rows, kMinusInf));
  }
  std::vector<double> d(components.size());
  std::vector<double> each(c.experiments.size());
  for (std::size_t r = 0; r < rows; ++r) {
    if (!s.singular[r].empty()) continue;
    distance->Evaluate(std::span(s.run).subspan(r * s.run_size, s.run_size), d);
    std::fill(each.begin(), each.end(), 0.0);
    std::size_t t = 0;
    for (std::size_t k = 0; k < components.size(); ++k) {
      double& ll = each[experiment_of[k]];
      switch (components[k].kind) {
        case ComponentKind::kNegLogLikelihood:
          ll -= d[k] / thresholds[t++];
          break;
        case ComponentKind::kThreshold:
          if (!(d[k] <= thresholds[t++])) ll = kMinusInf;
          break;
        case ComponentKind::kIndicator:
          if (d[k] != components[k].required) ll = kMinusInf;
          break;
      }
    }
    double ll = 0.0;
    for (std::size_t e = 0; e < each.size(); ++e) {
      ll += each[e];
      if (per_experiment != nullptr) (*per_experiment)[e][r] = each[e];
    }
    out[r] = ll;
  }
  return out;
}

// The campaign view (docs/algorithm.md, "Which experiment decided which clamp"): each clamp's
// P(fixed) with each experiment's likelihood alone, and with all of them, over the truths'
// neighbourhoods (the other clamps held at each truth's values), averaged over the truths. The
// run's particles cannot give it: where the joint data decide a clamp the population holds no
// particle with it flipped, and reweighting them by one experiment would credit that experiment
// with what the others decided.
CampaignView MakeCampaignView(const CalibrationConfig& c,
                              const design::LocalPopulation& local,
                              const std::vector<double>& log_prior,
                              const std::vector<std::vector<double>>& per_experiment,
                              const std::vector<double>& joint,
                              std::vector<double> run_p_fixed,
                              double identified_margin) {
  const auto d = static_cast<std::size_t>(local.dimension);
  auto p_fixed = [&](const std::vector<double>& ll) {
    std::vector<double> p(d, 0.0);
    for (const design::Neighbourhood& nb : local.truths) {
      std::vector<double> lw(nb.rows.size());
      for (std::size_t i = 0; i < lw.size(); ++i) {
        const auto row = static_cast<std::size_t>(nb.rows[i]);
        lw[i] = log_prior[row] + ll[row];
      }
      const std::vector<double> correct = design::ProbabilityOfTruth(nb, lw);
      const std::uint8_t* truth = local.bits.data() + static_cast<std::size_t>(nb.rows.front()) * d;
      for (std::size_t k = 0; k < d; ++k) {
        const double q = correct[static_cast<std::size_t>(local.free_of_bit[k])];
        p[k] += truth[k] ? q : 1.0 - q;
      }
    }
    for (double& v : p) v /= static_cast<double>(local.truths.size());
    return p;
  };
  CampaignView view;
  view.clamp_names = c.space.names;
  view.clamps_per_edge = c.model.clamps_per_edge;
  view.length_m = c.model.length;
  view.identified_margin = identified_margin;
  view.run_p_fixed = std::move(run_p_fixed);
  view.together = p_fixed(joint);
  for (std::size_t e = 0; e < c.experiments.size(); ++e) {
    const std::string& name = c.experiments[e].name;
    view.alone.push_back(
        {name.empty() ? "experiment " + std::to_string(e + 1) : name, p_fixed(per_experiment[e])});
  }
  return view;
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
    // Across the strip in mm from edge 1 (y = 0), as the bench measures it.
    const double width = c.model.width * 1000;
    ident << k + 1 << ",\"load " << DesignNumber(d.load_x * 100) << " cm, "
          << DesignNumber(d.load_y_fraction * width) << " mm from edge 1; scan "
          << DesignNumber(d.scan_from * 100) << "-" << DesignNumber(d.scan_to * 100) << " cm, "
          << DesignNumber(d.scan_y_fraction * width) << " mm from edge 1\"";
    for (double v : r.scores[k].identifiability) ident << ',' << DesignNumber(v);
    ident << '\n';
  }
  if (!o.next_config.empty()) dir.Add("next.toml") << o.next_config;
  if (!o.campaign.alone.empty()) WriteCampaignCsv(dir.Add("campaign.csv"), o.campaign);
}

// What design needs of the config: a [design] table, the built-in sensor and no continuous
// unknowns.
void CheckDesignConfig(const CalibrationConfig& c) {
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
}

// The stop rule (every clamp decided, or no candidate expected to decide another one) and why
// each clamp the run leaves undecided stays so.
void JudgeClamps(const CalibrationConfig& c,
                 const std::vector<double>& marginals,
                 double identified_margin,
                 std::size_t best,
                 DesignOutcome& o) {
  // The stop rule: every clamp decided, or no candidate expected to decide another one.
  if (o.decided_now >= o.clamps) {
    o.stop = true;
    o.stop_reason = "every clamp is decided";
  } else if (o.expected_decided - o.decided_now < 0.5) {
    o.stop = true;
    char adds[32];
    std::snprintf(adds, sizeof adds, "%.1f", o.expected_decided - o.decided_now);
    o.stop_reason = "no candidate is expected to decide another clamp (the best, the load at " +
                    DesignNumber(o.candidates[best].load_x * 100) + " cm, adds " + adds + ")";
  }
  for (int k = 0; k < o.clamps; ++k) {
    if (std::abs(marginals[static_cast<std::size_t>(k)] - 0.5) > identified_margin) {
      continue;
    }
    // The strongest evidence any candidate alone gives against flipping it.
    double signal = std::numeric_limits<double>::quiet_NaN();
    for (const design::Score& score : o.result.scores) {
      const double v = score.flip_signal[static_cast<std::size_t>(k)];
      if (std::isfinite(v) && !(v <= signal)) signal = v;
    }
    UndecidedClamp u;
    u.bit = k;
    u.where = ClampWhere(c, k);
    u.reason = !std::isfinite(signal) ? "no candidate's data were simulated against its flip"
               : signal < 2.0
                   ? "flipping it changes no candidate's profile by more than the noise (the "
                     "response there is below the noise)"
                   : "its flip shows in a profile, but another clamp (its mirror across the strip "
                     "or a neighbour) can be flipped with it for nearly the same profile";
    o.undecided.push_back(std::move(u));
  }
}

// identifiability.<fmt> for each figure format; with --posterior also campaign.<fmt>, which
// experiment decided what: drawn by combabc_design.py into the staged folder.
void DrawFigures(const CalibrationConfig& c, const DesignOutcome& o, OutputDirectory& dir) {
  const PythonScript script = FindPythonScript(
      "combabc_design.py", "COMBABC_DESIGN_SCRIPT", "python3-numpy and python3-matplotlib");
  std::vector<std::string> tables{"identifiability"};
  if (!o.campaign.alone.empty()) tables.emplace_back("campaign");
  for (const std::string& format : c.output.figure_formats) {
    for (const std::string& table : tables) {
      std::string name = table;
      name += ".";
      name += format;
      dir.Add(name);
      const ProcessResult result = RunProcess({script.python,
                                               script.script,
                                               dir.StagedPath(table + ".csv"),
                                               dir.StagedPath(name),
                                               format},
                                              "python3-numpy and python3-matplotlib");
      if (result.status != 0) {
        throw Error(KindOfScriptStatus(result.status),
                    name + ": " + ScriptMessage(result.err, result.status, "combabc_design"));
      }
    }
  }
}

// The clamps the marginals decide: P(fixed) farther than `margin` from 0.5.
int Decided(const std::vector<double>& marginals, double margin) {
  int count = 0;
  for (double p : marginals) count += std::abs(p - 0.5) > margin;
  return count;
}

// Design from a finished run's posterior (--posterior): the truths' neighbourhoods simulated and
// scored. Returns the run's marginals.
std::vector<double> DesignFromPosterior(const DesignRequest& request,
                                        const CalibrationConfig& c,
                                        const design::DesignOptions& options,
                                        int threads,
                                        std::chrono::steady_clock::time_point simulate_start,
                                        DesignOutcome& o) {
  // The run's particles are too few to stand for what a new experiment's data would leave
  // (reweighted, they collapse onto a handful and every clamp looks decided): the truths'
  // neighbourhoods under the prior and the run's own likelihood instead (docs/algorithm.md,
  // "Honest predictions").
  std::vector<double> thresholds;
  const design::Population known =
      FromPosterior(request.posterior_path, c, &o.population, &thresholds);
  std::vector<double> marginals = design::Marginals(known);
  o.decided_now = Decided(marginals, options.identified_margin);
  design::LocalPopulation local =
      Neighbourhoods(c, known, design::DrawTruths(known.weights, options.truths, options.seed));
  const DesignMemory memory = EstimateDesignMemory(c, static_cast<double>(local.rows()));
  if (memory.total() > c.model.memory_limit_bytes) {
    throw Error(ErrorKind::kUsage,
                "the truths' neighbourhoods hold " + std::to_string(local.rows()) +
                    " configurations, which would need about " +
                    DesignNumber(memory.total() / 1e9) + " GB of memory to design from (limit " +
                    DesignNumber(c.model.memory_limit_bytes / 1e9) +
                    " GB); fewer truths or scan points in [design], or raise memory_limit_gb",
                request.posterior_path,
                0,
                "--posterior");
  }
  const Simulated s = SimulateRows(c, local.bits, local.rows(), threads, true);
  std::vector<std::vector<double>> per_experiment;
  const std::vector<double> ll =
      RunLogLikelihood(c, s, thresholds, request.posterior_path, &per_experiment);
  o.campaign = MakeCampaignView(
      c, local, local.log_weight, per_experiment, ll, marginals, c.design->identified_margin);
  for (std::size_t r = 0; r < local.rows(); ++r) {
    local.log_weight[r] += ll[r];
    if (!s.singular[r].empty()) {
      if (o.singular == 0) o.singular_reason = s.singular[r];
      ++o.singular;
    }
  }
  o.simulated = local.rows();
  o.simulate_seconds = SecondsSince(simulate_start);
  o.particles = known.size();
  o.method =
      "each truth's neighbourhood (the truths, their one-bit flips, the swaps of mirror and "
      "neighbouring clamps and their mirror images) under the prior and the run's likelihood";
  o.result = design::ScoreNeighbourhoods(local, s.profiles, options);
  // The neighbourhoods' own count before any new data stands in for the run's (each truth's
  // flips are judged with the others held at the truth's values): what a candidate adds to it
  // is added to what the run decided.
  o.expected_decided =
      o.decided_now +
      std::max(0.0, o.result.cumulative.front().identified - o.result.prior_identified);
  return marginals;
}

}  // namespace

DesignOutcome RunDesign(const DesignRequest& request) {
  const auto start = std::chrono::steady_clock::now();
  CalibrationConfig c = LoadConfig(request.config_path);
  CheckDesignConfig(c);
  const int threads = request.threads >= 0 ? request.threads : c.smc.threads;
  const std::string directory =
      request.output_directory.empty()
          ? (fs::path(ResolvePath(c.directory, c.output.directory)) / "design")
                .lexically_normal()
                .string()
          : request.output_directory;
  // Refused now rather than after the simulations; the parent folder is made only at the end.
  const fs::path parent = fs::path(directory).parent_path();
  std::error_code ec;
  if (parent.empty() || fs::exists(parent, ec)) {
    OutputDirectory::Check(directory, request.overwrite);
  }

  DesignOutcome o;
  o.noise_sigma = c.design->noise;
  o.width = c.model.width;
  o.clamps = c.space.dimension;
  o.candidates = Candidates(*c.design);
  design::DesignOptions options;
  options.noise_sigma = c.design->noise;
  options.truths = c.design->truths;
  options.select = c.design->select;
  options.identified_margin = c.design->identified_margin;
  options.seed = c.smc.seed;
  options.threads = threads;
  std::vector<double> marginals;
  const auto simulate_start = std::chrono::steady_clock::now();
  if (request.posterior_path.empty()) {
    design::Population population = FromPrior(c, &o.population);
    o.exhaustive = BinarySpace(c.space).num_free() <= kDesignExactBits;
    const std::vector<design::CandidateProfiles> profiles =
        SimulateCandidates(c, population, threads, o);
    o.simulated = population.size() + o.singular;
    o.simulate_seconds = SecondsSince(simulate_start);
    o.particles = population.size();
    o.method = o.exhaustive ? "every configuration, reweighted by each truth's data"
                            : "the prior draws, reweighted by each truth's data";
    o.result = design::ScoreCandidates(population, profiles, options);
    marginals = design::Marginals(population);
    o.decided_now = Decided(marginals, options.identified_margin);
    o.expected_decided = o.result.cumulative.front().identified;
  } else {
    marginals = DesignFromPosterior(request, c, options, threads, simulate_start, o);
  }
  const std::size_t best = static_cast<std::size_t>(o.result.selected.front());
  JudgeClamps(c, marginals, options.identified_margin, best, o);
  const fs::path design_directory = fs::absolute(directory);
  if (!o.stop) {
    const NextStep next = WriteNextConfig(c, o.candidates[best], design_directory);
    o.next_config = next.config_text;
    o.next_config_path = (fs::path(directory) / "next.toml").string();
    o.next_data_path = next.data_path;
    o.instructions = Instructions(c, o.candidates[best], next, o.next_config_path);
  }

  if (!parent.empty() && !fs::exists(parent, ec)) {
    fs::create_directories(parent, ec);
    if (ec) {
      throw Error(
          ErrorKind::kCantCreate, "cannot create directory: " + ec.message(), parent.string());
    }
  }
  OutputDirectory dir(directory, request.overwrite);
  WriteFiles(dir, o, c);
  if (request.figure) DrawFigures(c, o, dir);
  dir.Commit();
  o.directory = directory;
  o.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return o;
}

std::optional<CampaignView> RunCampaignView(const std::string& history_path, std::string* why_not) {
  const RunMetadata metadata = HistoryStore::Open(history_path, /*read_only=*/true).LoadMetadata();
  CalibrationConfig c;
  try {
    c = ParseConfig(metadata.config_text, metadata.config_path);
  } catch (const Error&) {
    return std::nullopt;  // a config this version no longer reads: no sensor to simulate
  }
  if (c.simulator.kind != SimulatorKind::kSensor || c.experiments.size() < 2) return std::nullopt;
  try {
    if (!c.reals.empty()) {
      throw Error(ErrorKind::kUsage,
                  "the run has continuous parameters ([parameters]); the view judges the bits "
                  "with them fixed");
    }
    design::DesignOptions defaults;
    const int truths = c.design ? c.design->truths : defaults.truths;
    const double margin = c.design ? c.design->identified_margin : defaults.identified_margin;
    std::string what;
    std::vector<double> thresholds;
    const design::Population known = FromPosterior(history_path, c, &what, &thresholds);
    design::LocalPopulation local =
        Neighbourhoods(c, known, design::DrawTruths(known.weights, truths, c.smc.seed));
    const Simulated s = SimulateRows(c, local.bits, local.rows(), c.smc.threads, true);
    std::vector<std::vector<double>> per_experiment;
    const std::vector<double> ll =
        RunLogLikelihood(c, s, thresholds, history_path, &per_experiment);
    return MakeCampaignView(
        c, local, local.log_weight, per_experiment, ll, design::Marginals(known), margin);
  } catch (const Error& e) {
    if (why_not != nullptr) *why_not = e.what();
    return std::nullopt;
  }
}

}  // namespace combabc::services
