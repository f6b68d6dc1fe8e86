// [model_choice]: the candidate models of an ABC model choice (docs/config.md, "Model choice").
// Each [[model_choice.model]] gives a name, a prior probability and the [model] keys (or the
// [simulator] table) that differ from the file's; its whole config is the file with those set,
// read like any config so that a bad key is refused at its own line.
#include "config_model_choice.hpp"

#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>
#include <utility>

#include "combabc/config/config.hpp"
#include "combabc/core/error.hpp"

namespace combabc::config_internal {
namespace {

// Sets `over`'s keys into `base`, table into table, moving the nodes so that they keep their
// source lines (a copy would lose them), and returns the key of a value that would replace a table
// or be replaced by one (refused by the caller), or "".
std::string MergeInto(toml::table& base, toml::table& over, const std::string& prefix) {
  for (auto it = over.begin(); it != over.end(); ++it) {
    const std::string key(it->first.str());
    toml::node& node = it->second;
    std::string name = prefix;
    name.append(".").append(key);
    toml::node* existing = base.get(key);
    if (existing != nullptr && existing->is_table() && node.is_table()) {
      std::string bad = MergeInto(*existing->as_table(), *node.as_table(), name);
      if (!bad.empty()) return bad;
      continue;
    }
    if (existing != nullptr && existing->is_table() != node.is_table()) return name;
    node.visit([&base, &key](auto& concrete) { base.insert_or_assign(key, std::move(concrete)); });
  }
  return "";
}

// The experiments are common to all models: their loads and scans ([model.load], [model.output])
// belong at the top of the file, where every model sees them.
constexpr const char* kCommonModelKeys[] = {"load", "output"};

}  // namespace

void ParseModelChoice(TableReader& root, CalibrationConfig* c) {
  auto table = root.Table("model_choice");
  if (!table) return;
  ModelChoiceConfig choice;
  choice.line = table->line();
  std::vector<TableReader> models = table->Tables("model");
  const auto reference = table->String("reference");
  const auto method = table->String("method");
  table->Finish();
  if (method && *method != "evidence" && *method != "joint") {
    table->Fail("method",
                "unknown method " + Excerpt(*method) +
                    "; expected \"evidence\" (each model's own run) or \"joint\" (one run over "
                    "the models and their parameters)");
  }
  choice.joint = method && *method == "joint";
  if (models.size() < 2) {
    table->Fail("model",
                "lists " + std::to_string(models.size()) +
                    " model(s); model choice needs at least two [[model_choice.model]] tables");
  }
  int with_prior = 0;
  double sum = 0.0;
  for (std::size_t k = 0; k < models.size(); ++k) {
    TableReader& m = models[k];
    CandidateModel model;
    model.line = m.line();
    const auto name = m.String("name");
    if (!name) m.Fail("name", "is required (a name for the model, e.g. \"clamped\")");
    if (!ValidModelName(*name)) {
      m.Fail("name", Excerpt(*name) + " is not a valid model name: " + kModelNameRule);
    }
    for (const CandidateModel& other : choice.models) {
      if (other.name == *name) {
        m.Fail("name",
               "model " + Excerpt(*name) + " is defined twice (first at line " +
                   std::to_string(other.line) + ")");
      }
    }
    model.name = *name;
    if (m.Has("prior")) {
      model.prior = m.NumberIn("prior", 0.0, 0.0, 1.0);
      sum += model.prior;
      ++with_prior;
    }
    if (const toml::node* over = m.Raw("model")) {
      if (!over->is_table()) m.Fail("model", "expected a table of [model] keys");
      for (const char* common : kCommonModelKeys) {
        if (const toml::node* node = over->as_table()->get(common)) {
          m.FailAt(*node,
                   m.Key("model") + "." + common,
                   std::string("the experiments are common to all models: set [model.") + common +
                       "] at the top of the file, not per model");
        }
      }
    }
    if (const toml::node* sim = m.Raw("simulator")) {
      if (!sim->is_table()) m.Fail("simulator", "expected a [simulator] table");
    }
    m.Finish();
    choice.models.push_back(std::move(model));
  }
  if (with_prior == 0) {
    for (CandidateModel& m : choice.models) {
      m.prior = 1.0 / static_cast<double>(choice.models.size());
    }
  } else if (with_prior < static_cast<int>(models.size())) {
    for (TableReader& m : models) {
      if (!m.Has("prior")) m.Fail("prior", "is missing: give every model a prior, or none");
    }
  } else if (std::abs(sum - 1.0) > 1e-9) {
    std::ostringstream os;
    os.precision(12);
    os << sum;
    models.back().Fail("prior", "the models' priors sum to " + os.str() + "; they must sum to 1");
  }
  for (std::size_t k = 0; choice.joint && k + 1 < choice.models.size(); ++k) {
    // The stick-breaking indicator gives model k the bit P = pi_k / (1 - pi_1 - ... - pi_{k-1}):
    // a model of prior 0 before the last would end the stick.
    if (!(choice.models[k].prior > 0.0)) {
      models[k].Fail("prior",
                     "is 0: with method = \"joint\" every model but the last needs a prior above "
                     "0 (or leave the model out)");
    }
  }
  if (reference) {
    bool found = false;
    for (std::size_t k = 0; k < choice.models.size(); ++k) {
      if (choice.models[k].name == *reference) {
        choice.reference = k;
        found = true;
      }
    }
    if (!found) {
      std::string names;
      for (const CandidateModel& m : choice.models) {
        names += (names.empty() ? "\"" : ", \"") + m.name + "\"";
      }
      table->Fail("reference",
                  "model " + Excerpt(*reference) + " is not defined; the models are " + names);
    }
  }
  c->model_choice = std::move(choice);
}

void BuildCandidateConfigs(CalibrationConfig* c) {
  if (!c->model_choice) return;
  std::vector<CandidateModel>& models = c->model_choice->models;
  std::vector<CalibrationConfig> configs;
  for (std::size_t k = 0; k < models.size(); ++k) {
    std::string where = "model_choice.model[" + std::to_string(k) + "] (" + models[k].name + ")";
    // A fresh parse per model: the nodes moved below leave it.
    toml::table root = toml::parse(c->text, c->path);
    toml::table& entry = *root["model_choice"]["model"].as_array()->get(k)->as_table();
    if (toml::table* over = entry["model"].as_table()) {
      if (root["model"].as_table() == nullptr) root.insert("model", toml::table{});
      const std::string bad = MergeInto(*root["model"].as_table(), *over, "model");
      if (!bad.empty()) {
        throw Error(ErrorKind::kConfig,
                    "is a table in one of [model] and " + where + " and a value in the other",
                    c->path,
                    models[k].line,
                    where.append(".").append(bad));
      }
    }
    if (toml::node* sim = entry.get("simulator")) {
      root.insert_or_assign("simulator", std::move(*sim->as_table()));
    }
    root.erase("model_choice");
    // Model k > 0 runs on seed + k: independent runs, as the errors of the model probabilities
    // assume (one seed for all would give identical models identical histories). Model 0's run
    // is the one its config alone would give.
    if (k > 0) {
      if (root["sampler"].as_table() == nullptr) root.insert("sampler", toml::table{});
      root["sampler"].as_table()->insert_or_assign(
          "seed", static_cast<std::int64_t>(c->smc.seed + static_cast<std::uint64_t>(k)));
    }
    std::ostringstream text;
    text << root;
    models[k].config_text = text.str() + "\n";
    try {
      configs.push_back(ParseConfigTable(root, models[k].config_text, c->path));
    } catch (const Error& e) {
      throw Error(
          e.kind(), e.message() + " (in " + where + ")", e.file(), e.line(), e.field(), e.column());
    }
    const CalibrationConfig& m = configs.back();
    if (m.low_fidelity) {
      throw Error(ErrorKind::kConfig,
                  "model choice needs single-fidelity runs (their signed weights estimate no "
                  "evidence): remove [simulator.low_fidelity]",
                  c->path,
                  models[k].line,
                  where);
    }
    // Comparable evidences need the same data, distance and final thresholds, and so the same
    // outputs: each model simulates every experiment at the same coordinates.
    const CalibrationConfig& first = configs.front();
    for (std::size_t e = 0; e < m.experiments.size() && k > 0; ++e) {
      if (m.experiments[e].output_coordinates != first.experiments[e].output_coordinates) {
        throw Error(ErrorKind::kConfig,
                    "simulates experiment " + std::to_string(e + 1) +
                        " at other output coordinates than model \"" + models[0].name +
                        "\": the models must give the same outputs, compared with the same data",
                    c->path,
                    models[k].line,
                    where);
      }
    }
  }
}

}  // namespace combabc::config_internal

namespace combabc {

bool ValidModelName(const std::string& name) {
  if (name.empty() || name.size() > 64 || name == "." || name == "..") return false;
  for (const char ch : name) {
    const bool ok = (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') ||
                    (ch >= '0' && ch <= '9') || ch == '_' || ch == '-' || ch == '.';
    if (!ok) return false;
  }
  return true;
}

}  // namespace combabc
