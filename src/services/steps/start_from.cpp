#include "services/steps/start_from.hpp"

#include <cmath>
#include <limits>
#include <map>

#include "combabc/core/error.hpp"
#include "combabc/history/history_store.hpp"

namespace combabc::services {
namespace {

[[noreturn]] void Refuse(const char* option, const std::string& why, const std::string& path) {
  throw Error(ErrorKind::kConfig, std::string(option) + ": " + why, path);
}

// The finished run's bits and reals must be the new run's, by name and in order.
void CheckSameParameters(const char* option,
                         const RunMetadata& m,
                         const ParameterSpace& space,
                         const std::string& path) {
  const BinarySpace& bits = space.binary();
  std::vector<std::string> names;
  names.reserve(static_cast<std::size_t>(bits.dimension()));
  for (int k = 0; k < bits.dimension(); ++k) names.push_back(bits.name(k));
  if (m.bit_names != names) {
    Refuse(option,
           "the finished run has " + std::to_string(m.bit_names.size()) + " bits, this config " +
               std::to_string(names.size()) +
               " (or other names): a run can only add experiments to the same parameters",
           path);
  }
  const auto& reals = space.reals();
  bool same_reals = m.reals.size() == reals.size();
  for (std::size_t r = 0; same_reals && r < reals.size(); ++r) {
    same_reals = m.reals[r].name == reals[r].name;
  }
  if (!same_reals) {
    Refuse(option, "the finished run's continuous parameters differ from this config's", path);
  }
}

const WaveRecord& LastCompleteWave(const char* option,
                                   const RunHistory& history,
                                   const std::string& path) {
  const WaveRecord* last = nullptr;
  for (const WaveRecord& w : history.waves) {
    if (w.complete && !w.particles.empty()) last = &w;
  }
  if (!last) Refuse(option, "the run has no complete wave to start from", path);
  return *last;
}

// The finished run's experiments must be this config's, with the same data, and the config must
// add at least one.
void CheckExperimentsKept(const RunMetadata& m, const Problem& p, const std::string& path) {
  const std::vector<MeasuredProfile> old_data = StoredProfiles(m, path);
  const std::vector<StoredExperiment> now = ExperimentsOf(p);
  for (std::size_t e = 0; e < m.experiments.size(); ++e) {
    const std::string& name = m.experiments[e].name;
    std::size_t match = now.size();
    for (std::size_t x = 0; x < now.size(); ++x) {
      if (now[x].name == name) match = x;
    }
    const std::string label = name.empty() ? "its experiment" : "experiment \"" + name + "\"";
    if (match == now.size()) Refuse("--from", label + " is not in this config", path);
    if (p.data[match].positions != old_data[e].positions ||
        p.data[match].values != old_data[e].values) {
      Refuse("--from", label + "'s measured data differ from those the finished run used", path);
    }
  }
  if (now.size() <= m.experiments.size()) {
    Refuse("--from",
           "this config adds no experiment to the finished run's " +
               std::to_string(m.experiments.size()),
           path);
  }
}

// The last wave's particles and weights, with the thresholds of the components the finished run
// had (by name) and infinity for the new ones; for a deterministic simulator, each particle's
// distances for those components, which wave 0 must simulate again.
StartPopulation PopulationOf(const RunMetadata& m,
                             const WaveRecord& last,
                             const std::vector<DistanceComponent>& components,
                             bool deterministic) {
  std::map<std::string, std::pair<std::size_t, double>> old_slot;  // name -> (component, eps)
  std::size_t slot = 0;
  for (std::size_t k = 0; k < m.distance_components.size(); ++k) {
    if (m.distance_components[k].kind == ComponentKind::kIndicator) continue;
    old_slot[m.distance_components[k].name] = {k, last.thresholds.at(slot++)};
  }
  StartPopulation start;
  std::vector<std::ptrdiff_t> old_component(components.size(), -1);
  for (std::size_t k = 0; k < components.size(); ++k) {
    const auto it = old_slot.find(components[k].name);
    if (it != old_slot.end()) old_component[k] = static_cast<std::ptrdiff_t>(it->second.first);
    if (components[k].kind == ComponentKind::kIndicator) continue;
    start.thresholds.push_back(it != old_slot.end() ? it->second.second
                                                    : std::numeric_limits<double>::infinity());
  }
  for (const Particle& particle : last.particles) {
    start.thetas.push_back(particle.theta);
    start.weights.push_back(std::max(particle.weight, 0.0));
    if (!deterministic) continue;
    std::vector<double> expected(components.size(), std::numeric_limits<double>::quiet_NaN());
    for (std::size_t k = 0; k < components.size(); ++k) {
      if (old_component[k] >= 0) {
        expected[k] = particle.distance.at(static_cast<std::size_t>(old_component[k]));
      }
    }
    start.expected.push_back(std::move(expected));
  }
  return start;
}

}  // namespace

StartPopulation StartFromFinishedRun(const std::string& history_path, const Problem& p) {
  const HistoryStore store = HistoryStore::Open(history_path, true);
  const RunMetadata m = store.LoadMetadata();
  const RunHistory history = store.LoadHistory();
  CheckSameParameters("--from", m, *p.space, history_path);
  const WaveRecord& last = LastCompleteWave("--from", history, history_path);
  CheckExperimentsKept(m, p, history_path);
  const bool deterministic = p.config.simulator.kind == SimulatorKind::kSensor;
  return PopulationOf(m, last, p.distance->components(), deterministic);
}

StartPopulation StartFromFinishedRun(const std::string& history_path,
                                     const ParameterSpace& space,
                                     const std::vector<DistanceComponent>& components) {
  const HistoryStore store = HistoryStore::Open(history_path, true);
  const RunMetadata m = store.LoadMetadata();
  CheckSameParameters("start_from", m, space, history_path);
  const RunHistory history = store.LoadHistory();
  return PopulationOf(m, LastCompleteWave("start_from", history, history_path), components, false);
}

std::pair<std::string, std::string> StartFingerprint(const std::string& history_path) {
  const RunMetadata m = HistoryStore::Open(history_path, true).LoadMetadata();
  for (const auto& [part, digest] : m.fingerprint) {
    if (part == "combined") return {"start", digest};
  }
  return {"start", "0000000000000000"};
}

}  // namespace combabc::services
