#include "services/start_from.hpp"

#include <cmath>
#include <limits>
#include <map>

#include "combabc/core/error.hpp"
#include "combabc/history/history_store.hpp"

namespace combabc::services {
namespace {

[[noreturn]] void Refuse(const std::string& why, const std::string& path) {
  throw Error(ErrorKind::kConfig, "--from: " + why, path);
}

}  // namespace

StartPopulation StartFromFinishedRun(const std::string& history_path, const Problem& p) {
  const HistoryStore store = HistoryStore::Open(history_path, true);
  const RunMetadata m = store.LoadMetadata();
  const RunHistory history = store.LoadHistory();
  const BinarySpace& bits = p.space->binary();
  std::vector<std::string> names;
  names.reserve(static_cast<std::size_t>(bits.dimension()));
  for (int k = 0; k < bits.dimension(); ++k) names.push_back(bits.name(k));
  if (m.bit_names != names) {
    Refuse("the finished run has " + std::to_string(m.bit_names.size()) + " bits, this config " +
               std::to_string(names.size()) +
               " (or other names): a run can only add experiments to the same parameters",
           history_path);
  }
  const auto& reals = p.space->reals();
  bool same_reals = m.reals.size() == reals.size();
  for (std::size_t r = 0; same_reals && r < reals.size(); ++r) {
    same_reals = m.reals[r].name == reals[r].name;
  }
  if (!same_reals) {
    Refuse("the finished run's continuous parameters differ from this config's", history_path);
  }
  const WaveRecord* last = nullptr;
  for (const WaveRecord& w : history.waves) {
    if (w.complete && !w.particles.empty()) last = &w;
  }
  if (!last) Refuse("the run has no complete wave to start from", history_path);
  // The finished run's experiments must be this config's, with the same data.
  const std::vector<MeasuredProfile> old_data = StoredProfiles(m, history_path);
  const std::vector<StoredExperiment> now = ExperimentsOf(p);
  for (std::size_t e = 0; e < m.experiments.size(); ++e) {
    const std::string& name = m.experiments[e].name;
    std::size_t match = now.size();
    for (std::size_t x = 0; x < now.size(); ++x) {
      if (now[x].name == name) match = x;
    }
    const std::string label = name.empty() ? "its experiment" : "experiment \"" + name + "\"";
    if (match == now.size()) Refuse(label + " is not in this config", history_path);
    if (p.data[match].positions != old_data[e].positions ||
        p.data[match].values != old_data[e].values) {
      Refuse(label + "'s measured data differ from those the finished run used", history_path);
    }
  }
  if (now.size() <= m.experiments.size()) {
    Refuse("this config adds no experiment to the finished run's " +
               std::to_string(m.experiments.size()),
           history_path);
  }
  // Components by name: the old ones' slots and final thresholds.
  std::map<std::string, std::pair<std::size_t, double>> old_slot;  // name -> (component, eps)
  std::size_t slot = 0;
  for (std::size_t k = 0; k < m.distance_components.size(); ++k) {
    if (m.distance_components[k].kind == ComponentKind::kIndicator) continue;
    old_slot[m.distance_components[k].name] = {k, last->thresholds.at(slot++)};
  }
  StartPopulation start;
  const auto components = p.distance->components();
  std::vector<std::ptrdiff_t> old_component(components.size(), -1);
  for (std::size_t k = 0; k < components.size(); ++k) {
    const auto it = old_slot.find(components[k].name);
    if (it != old_slot.end()) old_component[k] = static_cast<std::ptrdiff_t>(it->second.first);
    if (components[k].kind == ComponentKind::kIndicator) continue;
    start.thresholds.push_back(it != old_slot.end() ? it->second.second
                                                    : std::numeric_limits<double>::infinity());
  }
  const bool deterministic = p.config.simulator.kind == SimulatorKind::kSensor;
  for (const Particle& particle : last->particles) {
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

std::pair<std::string, std::string> StartFingerprint(const std::string& history_path) {
  const RunMetadata m = HistoryStore::Open(history_path, true).LoadMetadata();
  for (const auto& [part, digest] : m.fingerprint) {
    if (part == "combined") return {"start", digest};
  }
  return {"start", "0000000000000000"};
}

}  // namespace combabc::services
