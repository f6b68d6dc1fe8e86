// `combabc run` / `combabc enumerate` on a config with [model_choice]
// (include/combabc/services/model_choice_run.hpp).
#include "combabc/services/model_choice_run.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <sstream>

#include "combabc/config/config.hpp"
#include "combabc/config/model_choice_config.hpp"
#include "combabc/core/error.hpp"
#include "combabc/core/output_files.hpp"
#include "combabc/history/history_store.hpp"
#include "export/json_text.hpp"
#include "services/adapters/python_script.hpp"
#include "services/model_joint.hpp"
#include "services/steps/problem.hpp"
#include "services/steps/read_back.hpp"
#include "services/steps/worker_steps.hpp"

namespace combabc::services {
namespace fs = std::filesystem;
namespace {

using export_text::JsonNumber;
using export_text::JsonString;

// The config's common final thresholds (CommonFinalThresholds), a missing one named at
// [model_choice].
std::vector<double> ConfigFinalThresholds(const CalibrationConfig& config) {
  try {
    return CommonFinalThresholds(config.smc.thresholds);
  } catch (const Error& e) {
    throw Error(ErrorKind::kConfig,
                e.message() + "; give it a target",
                config.path,
                config.model_choice->line,
                "model_choice");
  }
}

CalibrationConfig LoadModelChoice(const std::string& config_path) {
  CalibrationConfig c = LoadConfig(config_path);
  if (!c.model_choice) {
    throw Error(ErrorKind::kConfig, "has no [model_choice] table", config_path);
  }
  return c;
}

std::string Output(const std::string& requested, const CalibrationConfig& c) {
  return requested.empty() ? ResolvePath(c.directory, c.output.directory) : requested;
}

// <directory>/models/, where each model's run gets its folder.
void CreateModelsFolder(const std::string& directory) {
  const fs::path models = fs::path(directory) / "models";
  std::error_code ec;
  fs::create_directories(models, ec);
  if (ec || !fs::is_directory(models, ec)) {
    throw Error(ErrorKind::kCantCreate,
                "cannot create the models' folder: " +
                    (ec ? ec.message() : std::string("a file of that name is in the way")),
                models.string());
  }
}

// waves.csv: the model probabilities after each wave (ModelProbabilitiesByWave), each model's
// evidence at its own wave's thresholds (its last wave's once its run has ended).
void WriteWaves(std::ostream& csv, const ModelChoiceOutcome& o) {
  csv << "wave,model,log_evidence,relative_se,probability,se,upper_bound_only,upper\n";
  const std::vector<std::vector<ModelProbability>> by_wave =
      o.joint ? o.by_wave : ModelProbabilitiesByWave(o.evidence);
  for (std::size_t t = 0; t < by_wave.size(); ++t) {
    for (std::size_t k = 0; k < by_wave[t].size(); ++k) {
      const ModelProbability& p = by_wave[t][k];
      const ModelEvidence& e = o.evidence[k];
      const std::size_t n = e.wave_log_evidence.size();
      const double nan = std::numeric_limits<double>::quiet_NaN();
      const double log_z = n == 0 ? nan : e.wave_log_evidence[std::min(t, n - 1)];
      const double r = n == 0 ? nan : e.wave_relative_se[std::min(t, n - 1)];
      csv << t + 1 << ',' << p.name << ',' << export_text::Number(log_z) << ','
          << export_text::Number(r) << ',' << export_text::Number(p.probability) << ','
          << export_text::Number(p.se) << ',' << (p.upper_bound_only ? 1 : 0) << ','
          << export_text::Number(p.upper) << '\n';
    }
  }
}

// bits.csv of a joint model choice: each model's bits given the model.
void WriteJointBits(std::ostream& csv, const ModelChoiceOutcome& o) {
  csv << "model,bit,name,probability,se\n";
  for (std::size_t k = 0; k < o.model_bits.size(); ++k) {
    for (std::size_t b = 0; b < o.model_bits[k].size(); ++b) {
      csv << o.models[k].name << ',' << b + 1 << ',' << o.model_bit_names[k][b] << ','
          << export_text::Number(o.model_bits[k][b].value) << ','
          << export_text::Number(o.model_bits[k][b].se) << '\n';
    }
  }
}

constexpr const char* kFigureNeeds =
    "the figure needs Python 3 with matplotlib (Debian: apt-get install python3 "
    "python3-matplotlib), or COMBABC_PYTHON naming such a python";

// model_probabilities.png, drawn from the staged waves.csv by scripts/report/
// combabc_model_choice.py. Returns "" when drawn, else why not: the tables are written all the
// same (a missing python is a note, as the export's NetCDF file).
std::string DrawWaves(OutputDirectory& out) {
  const std::string figure = "model_probabilities.png";
  out.Add(figure);
  std::string why;
  try {
    const PythonScript tools =
        FindPythonScript("combabc_model_choice.py", "COMBABC_MODEL_CHOICE_SCRIPT", kFigureNeeds);
    const ProcessResult result = RunProcess({tools.python,
                                             tools.script,
                                             "--out",
                                             out.StagedPath(figure),
                                             "--",
                                             out.StagedPath("waves.csv")},
                                            kFigureNeeds);
    if (result.status == 0) return {};
    why = ScriptMessage(result.err, result.status, "combabc_model_choice");
  } catch (const Error& e) {
    if (e.kind() != ErrorKind::kCantCreate) throw;  // an interrupt, not a missing python
    why = e.message();
  }
  out.Discard(figure);
  return "the figure of the model probabilities per wave (" + figure + ") was not drawn: " + why;
}

// summary.json and models.csv in <directory>/model_choice/; for a run, waves.csv, and with
// `figure` its figure (ModelChoiceOutcome::note says why one was not drawn).
void WriteModelChoice(const std::string& directory,
                      bool overwrite,
                      ModelChoiceOutcome& o,
                      bool figure) {
  OutputDirectory out((fs::path(directory) / "model_choice").string(), overwrite);
  const ModelEvidence& reference = o.evidence[o.reference];
  std::ostream& json = out.Add("summary.json");
  json << "{\n  \"exact\": " << (o.exact ? "true" : "false") << ",\n  \"method\": "
       << (o.exact   ? "\"enumeration\""
           : o.joint ? "\"joint\""
                     : "\"evidence\"")
       << ",\n  \"reference\": " << JsonString(reference.name) << ",\n  \"models\": [\n";
  std::ostream& csv = out.Add("models.csv");
  csv << "model,prior,probability,se,upper_bound_only,upper,log_evidence,relative_se,"
         "log10_bayes_factor,reached,wave,simulations,termination\n";
  for (std::size_t k = 0; k < o.models.size(); ++k) {
    const ModelProbability& p = o.models[k];
    const ModelEvidence& e = o.evidence[k];
    const double log10_bf = (e.log_evidence - reference.log_evidence) / std::log(10.0);
    json << "    {\"name\": " << JsonString(p.name) << ", \"prior\": " << JsonNumber(p.prior)
         << ", \"probability\": " << JsonNumber(p.probability) << ", \"se\": " << JsonNumber(p.se)
         << ", \"upper_bound_only\": " << (p.upper_bound_only ? "true" : "false")
         << ", \"upper\": " << JsonNumber(p.upper)
         << ", \"log_evidence\": " << JsonNumber(e.log_evidence)
         << ", \"relative_se\": " << JsonNumber(e.relative_se)
         << ", \"log10_bayes_factor\": " << JsonNumber(log10_bf)
         << ", \"reached\": " << (e.reached ? "true" : "false") << ", \"wave\": " << e.wave + 1
         << ", \"simulations\": " << e.simulations
         << ", \"termination\": " << JsonString(e.termination) << "}"
         << (k + 1 < o.models.size() ? ",\n" : "\n");
    csv << p.name << ',' << export_text::Number(p.prior) << ','
        << export_text::Number(p.probability) << ',' << export_text::Number(p.se) << ','
        << (p.upper_bound_only ? 1 : 0) << ',' << export_text::Number(p.upper) << ','
        << export_text::Number(e.log_evidence) << ',' << export_text::Number(e.relative_se) << ','
        << export_text::Number(log10_bf) << ',' << (e.reached ? 1 : 0) << ',' << e.wave + 1 << ','
        << e.simulations << ',' << e.termination << '\n';
  }
  json << "  ]\n}\n";
  if (o.joint) WriteJointBits(out.Add("bits.csv"), o);
  if (!o.exact) {
    WriteWaves(out.Add("waves.csv"), o);
    if (figure) o.note = DrawWaves(out);
  }
  out.Commit();
}

// A model's run: a new one, or its history found in place (read when finished, else resumed).
RunOutcome RunModel(const RunRequest& request,
                    const CandidateModel& model,
                    const std::string& model_directory,
                    const std::string& database,
                    SmcObserver* progress) {
  const std::string history_path = (fs::path(model_directory) / database).string();
  std::error_code ec;
  if (!request.overwrite && fs::exists(fs::symlink_status(history_path, ec))) {
    const RunMetadata metadata = HistoryStore::Open(history_path, true).LoadMetadata();
    if (metadata.config_text != model.config_text) {
      throw Error(ErrorKind::kCantCreate,
                  "holds a run of model \"" + model.name +
                      "\" from another config; use --overwrite to start the models afresh, or -o "
                      "DIR",
                  history_path);
    }
    if (metadata.status == RunStatus::kFinished) {
      RunOutcome outcome;
      outcome.history_path = history_path;
      const HistoryStore store = HistoryStore::Open(history_path, true);
      outcome.history = store.LoadHistory();
      ReadBack back = ReadBackHistory(store);
      outcome.checks = std::move(back.checks);
      outcome.answer = std::move(back.answer);
      outcome.strip = std::move(back.strip);
      return outcome;
    }
    ResumeRequest resume;
    resume.history_path = history_path;
    resume.threads = request.threads;
    resume.report = request.report;
    resume.executor = request.executor;
    resume.on_checks_before = request.on_checks_before;
    resume.on_report_progress = request.on_report_progress;
    return ResumeCalibration(resume, progress);
  }
  RunRequest r = request;
  r.config_text = model.config_text;
  r.output_directory = model_directory;
  return RunCalibration(r, progress);
}

// The request's executor, for the steps that only its primary does (under MPI every rank runs the
// model choice; the models' runs cross the ranks, the tables are rank 0's alone).
std::unique_ptr<Executor> ExecutorOf(const ExecutorFactory& factory) {
  return factory ? factory(1) : std::make_unique<ThreadPoolExecutor>(1);
}

// The joint space's layout and each model's own bit names, from the models' configs.
struct JointModels {
  JointLayout layout;
  std::vector<std::vector<std::string>> bit_names;
};
JointModels JointModelsOf(const CalibrationConfig& c) {
  std::vector<std::string> names;
  std::vector<double> prior;
  std::vector<ModelParameters> parameters;
  JointModels out;
  for (const CandidateModel& model : c.model_choice->models) {
    const CalibrationConfig m = ParseConfig(model.config_text, c.path);
    names.push_back(model.name);
    prior.push_back(model.prior);
    parameters.push_back({m.space, m.reals, m.joint_priors});
    const BinarySpace bits(m.space);
    std::vector<std::string> bit_names;
    bit_names.reserve(static_cast<std::size_t>(bits.dimension()));
    for (int b = 0; b < bits.dimension(); ++b) bit_names.push_back(bits.name(b));
    out.bit_names.push_back(std::move(bit_names));
  }
  try {
    out.layout = BuildJointSpace(names, prior, parameters).layout;
  } catch (const Error& e) {
    throw Error(e.kind(), e.message(), c.path, c.model_choice->line, "model_choice");
  }
  return out;
}

// Model k's evidence from the joint run: Z_k = Z P(M_k | D) / pi_k, Z the joint run's evidence
// (sum_k pi_k Z_k), its relative error that of Z and of P(M_k | D) added in quadrature (taken as
// independent: an approximation).
ModelEvidence JointEvidence(const ModelEvidence& z, const ModelProbability& p) {
  ModelEvidence e = z;
  e.name = p.name;
  e.prior = p.prior;
  const double log_ratio = std::log(p.probability / p.prior);
  e.reached = z.reached && !p.upper_bound_only;
  e.log_evidence =
      e.reached ? z.log_evidence + log_ratio : -std::numeric_limits<double>::infinity();
  const double r = p.probability > 0.0 ? p.se / p.probability : 0.0;
  e.relative_se = std::sqrt(z.relative_se * z.relative_se + r * r);
  e.log_upper = z.log_upper + std::log(std::max(p.upper, p.probability) / p.prior);
  e.wave_log_evidence.clear();
  e.wave_relative_se.clear();
  return e;
}

// method = "joint": one run over the joint space (services/steps/problem.cpp's BuildJointModel),
// in <directory>/joint/, and the model probabilities read off its particles.
ModelChoiceOutcome RunJointModelChoice(
    const RunRequest& request,
    const CalibrationConfig& c,
    const std::string& directory,
    SmcObserver* progress,
    const std::function<void(const std::string&)>& before_model) {
  const std::vector<double> final_thresholds = ConfigFinalThresholds(c);
  const JointModels models = JointModelsOf(c);
  CandidateModel joint;
  joint.name = "joint";
  joint.config_text = c.text;
  if (before_model) before_model("joint");
  ModelChoiceOutcome o;
  o.joint = true;
  const std::string run_directory = (fs::path(directory) / "joint").string();
  RunOutcome run = RunModel(request, joint, run_directory, c.output.database, progress);
  if (run.history.summary.termination == Termination::kInterrupted) {
    o.interrupted = true;
    o.runs.push_back(std::move(run));
    return o;
  }
  const RunMetadata metadata = HistoryStore::Open(run.history_path, true).LoadMetadata();
  const ModelEvidence z =
      EstimateEvidence(run.history, metadata.distance_components, final_thresholds);
  const std::vector<WaveRecord>& waves = run.history.waves;
  for (const WaveRecord& wave : waves) {
    o.by_wave.push_back(JointModelProbabilities(wave, models.layout));
  }
  // The wave at the final thresholds; a run that never reached them answers from its last wave
  // with particles, and no model's evidence is reached.
  std::size_t at = waves.empty() ? 0 : waves.size() - 1;
  if (z.wave >= 0) {
    at = static_cast<std::size_t>(z.wave);
  } else {
    while (at > 0 && waves[at].particles.empty()) --at;
  }
  o.models = waves.empty() ? std::vector<ModelProbability>{} : o.by_wave[at];
  if (z.wave < 0) {
    // No wave at the final thresholds (a limit stopped the run): the wider thresholds'
    // probabilities are no answer, so each model has only the bound that says nothing.
    for (ModelProbability& p : o.models) {
      p.probability = std::numeric_limits<double>::quiet_NaN();
      p.se = 0.0;
      p.upper_bound_only = true;
      p.upper = 1.0;
    }
  }
  for (std::size_t k = 0; k < o.models.size(); ++k) {
    o.evidence.push_back(JointEvidence(z, o.models[k]));
    for (std::size_t t = 0; t < waves.size(); ++t) {
      const ModelProbability& p = o.by_wave[t][k];
      o.evidence[k].wave_log_evidence.push_back(z.wave_log_evidence[t] +
                                                std::log(p.probability / p.prior));
      o.evidence[k].wave_relative_se.push_back(z.wave_relative_se[t]);
    }
    o.model_bits.push_back(JointModelBits(waves[at], models.layout, k));
    o.model_bit_names.push_back(models.bit_names[k]);
  }
  o.reference = c.model_choice->reference;
  o.runs.push_back(std::move(run));
  o.directory = (fs::path(directory) / "model_choice").string();
  const std::unique_ptr<Executor> executor = ExecutorOf(request.executor);
  OnPrimary(*executor, [&] { WriteModelChoice(directory, request.overwrite, o, request.report); });
  return o;
}

}  // namespace

void CheckModelRuns(std::span<const ModelRun> models) {
  if (models.size() < 2) {
    throw Error(ErrorKind::kUsage,
                "model choice needs at least two models; got " + std::to_string(models.size()));
  }
  double sum = 0.0;
  for (std::size_t k = 0; k < models.size(); ++k) {
    const ModelRun& m = models[k];
    if (!ValidModelName(m.name)) {
      std::string shown = m.name.substr(0, 64);
      // One line, whatever the name holds.
      std::replace_if(
          shown.begin(), shown.end(), [](char ch) { return ch == '\n' || ch == '\r'; }, '?');
      throw Error(ErrorKind::kUsage,
                  "\"" + shown + "\" is not a valid model name: " + kModelNameRule);
    }
    for (std::size_t j = 0; j < k; ++j) {
      if (models[j].name == m.name) {
        throw Error(ErrorKind::kUsage, "model \"" + m.name + "\" is given twice");
      }
    }
    // Not a model of prior 0 either: its run could only cost simulations.
    if (!(m.prior > 0.0 && m.prior <= 1.0)) {
      std::ostringstream os;
      os << m.prior;
      throw Error(ErrorKind::kUsage,
                  "the prior of model \"" + m.name + "\" is " + os.str() +
                      "; each model's prior must be above 0 and at most 1");
    }
    sum += m.prior;
  }
  if (std::abs(sum - 1.0) > 1e-9) {
    std::ostringstream os;
    os.precision(12);
    os << sum;
    throw Error(ErrorKind::kUsage,
                "the models' priors sum to " + os.str() + "; they must sum to 1");
  }
}

std::vector<double> CommonFinalThresholds(std::span<const ThresholdSchedule> schedules) {
  std::vector<double> eps;
  for (std::size_t s = 0; s < schedules.size(); ++s) {
    const std::optional<double> end = FinalThreshold(schedules[s]);
    if (!end) {
      throw Error(ErrorKind::kUsage,
                  "threshold component " + std::to_string(s + 1) +
                      " has no final threshold (an adaptive schedule without target): model "
                      "choice compares the models' evidences at common final thresholds");
    }
    eps.push_back(*end);
  }
  return eps;
}

ModelChoiceOutcome CombineModelRuns(std::span<const ModelRun> models,
                                    std::size_t reference,
                                    const std::vector<double>& final_thresholds,
                                    const std::string& directory,
                                    bool overwrite,
                                    bool figure,
                                    const ExecutorFactory& executor) {
  ModelChoiceOutcome o;
  for (const ModelRun& model : models) {
    const HistoryStore store = HistoryStore::Open(model.history_path, true);
    const RunMetadata metadata = store.LoadMetadata();
    ModelEvidence e =
        EstimateEvidence(store.LoadHistory(), metadata.distance_components, final_thresholds);
    e.name = model.name;
    e.prior = model.prior;
    o.evidence.push_back(std::move(e));
  }
  o.reference = reference;
  o.models = ModelProbabilities(o.evidence);
  o.directory = (fs::path(directory) / "model_choice").string();
  const std::unique_ptr<Executor> primary = ExecutorOf(executor);
  OnPrimary(*primary, [&] { WriteModelChoice(directory, overwrite, o, figure); });
  return o;
}

bool HasModelChoice(const std::string& config_path) {
  return LoadConfig(config_path).model_choice.has_value();
}

ModelChoiceOutcome RunModelChoice(const RunRequest& request,
                                  SmcObserver* progress,
                                  const std::function<void(const std::string&)>& before_model) {
  if (!request.start_from.empty()) {
    throw Error(ErrorKind::kUsage,
                "--from does not apply to a model choice ([model_choice]): each model starts from "
                "its prior");
  }
  const CalibrationConfig c = LoadModelChoice(request.config_path);
  const std::string directory = Output(request.output_directory, c);
  if (c.model_choice->joint) {
    return RunJointModelChoice(request, c, directory, progress, before_model);
  }
  const std::vector<double> final_thresholds = ConfigFinalThresholds(c);
  const std::unique_ptr<Executor> executor = ExecutorOf(request.executor);
  OnPrimary(*executor, [&] { CreateModelsFolder(directory); });
  std::vector<RunOutcome> runs;
  std::vector<ModelRun> made;
  for (const CandidateModel& model : c.model_choice->models) {
    if (before_model) before_model(model.name);
    const std::string model_directory = (fs::path(directory) / "models" / model.name).string();
    RunOutcome run = RunModel(request, model, model_directory, c.output.database, progress);
    if (run.history.summary.termination == Termination::kInterrupted) {
      ModelChoiceOutcome o;
      o.interrupted = true;
      o.runs = std::move(runs);
      o.runs.push_back(std::move(run));
      return o;
    }
    made.push_back({model.name, model.prior, run.history_path});
    runs.push_back(std::move(run));
  }
  ModelChoiceOutcome o = CombineModelRuns(made,
                                          c.model_choice->reference,
                                          final_thresholds,
                                          directory,
                                          request.overwrite,
                                          request.report,
                                          request.executor);
  o.runs = std::move(runs);
  return o;
}

ModelChoiceOutcome EnumerateModelChoice(
    const EnumerateRequest& request,
    SmcObserver* progress,
    const std::function<void(const std::string&)>& before_model) {
  const CalibrationConfig c = LoadModelChoice(request.config_path);
  const std::string directory = request.output_directory.empty()
                                    ? (fs::path(Output("", c)) / kEnumerationFolder).string()
                                    : request.output_directory;
  const std::unique_ptr<Executor> executor = ExecutorOf(request.executor);
  OnPrimary(*executor, [&] { CreateModelsFolder(directory); });
  ModelChoiceOutcome o;
  o.exact = true;
  for (const CandidateModel& model : c.model_choice->models) {
    if (before_model) before_model(model.name);
    EnumerateRequest r = request;
    r.config_text = model.config_text;
    r.output_directory = (fs::path(directory) / "models" / model.name).string();
    EnumerateOutcome outcome = RunEnumeration(r, progress);
    if (outcome.interrupted) {
      o.interrupted = true;
      o.enumerations.push_back(std::move(outcome));
      return o;
    }
    ModelEvidence e;
    e.name = model.name;
    e.prior = model.prior;
    e.exact = true;
    e.reached = outcome.log_evidence > -std::numeric_limits<double>::infinity();
    e.log_evidence = outcome.log_evidence;
    e.log_upper = outcome.log_evidence;
    e.wave = 0;
    e.simulations = outcome.enumerated;
    e.termination = ToString(Termination::kEnumerated);
    o.evidence.push_back(e);
    o.enumerations.push_back(std::move(outcome));
  }
  o.reference = c.model_choice->reference;
  o.models = ModelProbabilities(o.evidence);
  o.directory = (fs::path(directory) / "model_choice").string();
  OnPrimary(*executor, [&] { WriteModelChoice(directory, request.overwrite, o, false); });
  return o;
}

std::string FormatModelProbabilities(const ModelChoiceOutcome& o) {
  std::ostringstream out;
  out << (o.exact   ? "Model probabilities (exact, by enumeration):\n"
          : o.joint ? "Model probabilities (one joint run over the models; +- one Monte-Carlo "
                      "standard error):\n"
                    : "Model probabilities (each model's evidence from its own run; +- one "
                      "Monte-Carlo standard error):\n");
  char line[256];
  const ModelEvidence& reference = o.evidence[o.reference];
  for (std::size_t k = 0; k < o.models.size(); ++k) {
    const ModelProbability& p = o.models[k];
    const ModelEvidence& e = o.evidence[k];
    if (p.upper_bound_only) {
      std::snprintf(line,
                    sizeof line,
                    "  %-20s prior %.3f  P < %.3g  (no particle at the final thresholds: %s)\n",
                    p.name.c_str(),
                    p.prior,
                    p.upper,
                    e.termination.c_str());
    } else if (o.exact) {
      std::snprintf(line,
                    sizeof line,
                    "  %-20s prior %.3f  P = %.4f  log10 B = %+.2f\n",
                    p.name.c_str(),
                    p.prior,
                    p.probability,
                    (e.log_evidence - reference.log_evidence) / std::log(10.0));
    } else {
      std::snprintf(line,
                    sizeof line,
                    "  %-20s prior %.3f  P = %.4f +- %.4f  log10 B = %+.2f\n",
                    p.name.c_str(),
                    p.prior,
                    p.probability,
                    p.se,
                    (e.log_evidence - reference.log_evidence) / std::log(10.0));
    }
    out << line;
  }
  out << "  (B: the Bayes factor against \"" << reference.name << "\")\n";
  return out.str();
}

std::string FormatJointModelBits(const ModelChoiceOutcome& o, std::size_t model) {
  if (!o.joint || model >= o.model_bits.size() || o.model_bits[model].empty()) return "";
  std::ostringstream out;
  out << "P(bit = 1 | model \"" << o.models[model].name << "\", data):\n";
  char line[256];
  for (std::size_t b = 0; b < o.model_bits[model].size(); ++b) {
    const WeightedMoment& m = o.model_bits[model][b];
    std::snprintf(line,
                  sizeof line,
                  "  %-20s %.3f +- %.3f\n",
                  o.model_bit_names[model][b].c_str(),
                  m.value,
                  m.se);
    out << line;
  }
  return out.str();
}

}  // namespace combabc::services
