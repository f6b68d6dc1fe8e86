// `combabc run` / `combabc enumerate` on a config with [model_choice].
#include "model_choice_command.hpp"

#include <iostream>

#include "combabc/config/config.hpp"
#include "combabc/core/error.hpp"
#include "combabc/services/model_choice_run.hpp"

namespace combabc::cli {
namespace {

// The model probabilities first, then each model's answer under its name.
template <typename Outcomes, typename Answer>
void PrintModelChoice(const Session& session,
                      bool quiet,
                      const services::ModelChoiceOutcome& outcome,
                      const Outcomes& per_model,
                      const Answer& answer_of) {
  if (!session.primary()) return;
  std::cout << services::FormatModelProbabilities(outcome);
  std::cout << "tables:  " << outcome.directory << "/summary.json, models.csv"
            << (outcome.exact ? "" : ", waves.csv") << (outcome.joint ? ", bits.csv" : "") << "\n";
  if (!outcome.note.empty()) std::cerr << "combabc: note: " << outcome.note << "\n";
  for (std::size_t k = 0; k < per_model.size(); ++k) {
    std::cout << "\n== model \"" << outcome.models[k].name << "\" ==\n";
    answer_of(per_model[k]);
  }
  (void)quiet;
}

}  // namespace

bool IsModelChoiceConfig(const std::string& config_path) {
  try {
    return LoadConfig(config_path).model_choice.has_value();
  } catch (const Error&) {
    return false;
  }
}

int RunModelChoiceCommand(services::RunRequest& request, bool quiet, const Session& session) {
  const std::vector<bool> temperatures = TemperatureSlotsOfConfig(request.config_path);
  return Guarded(session, quiet, temperatures, [&](SmcObserver* observer) {
    const auto announce = [&](const std::string& name) {
      if (session.primary() && !quiet) std::cerr << "model \"" << name << "\"\n";
    };
    const auto outcome = services::RunModelChoice(request, observer, announce);
    if (outcome.interrupted) {
      std::cerr << "interrupted; continue with: combabc run " << request.config_path
                << " (each model's history goes on where it stopped)\n";
      return kExitInterrupted;
    }
    const auto print_run = [&](const services::RunOutcome& run) {
      std::cout << run.history.summary.BriefReport() << "\n"
                << "history: " << run.history_path << "\n";
      PrintAnswer(session, quiet, run.answer, run.strip);
    };
    if (!outcome.joint) {
      PrintModelChoice(session, quiet, outcome, outcome.runs, print_run);
      return 0;
    }
    // One joint run: its answer (the indicator bits and every model's bits), then each model's
    // bits given the model.
    const std::vector<services::RunOutcome> none;
    PrintModelChoice(session, quiet, outcome, none, print_run);
    if (!session.primary()) return 0;
    std::cout << "\n== the joint run (all models) ==\n";
    print_run(outcome.runs.front());
    for (std::size_t k = 0; k < outcome.models.size(); ++k) {
      std::cout << "\n== model \"" << outcome.models[k].name << "\" ==\n"
                << services::FormatJointModelBits(outcome, k);
    }
    return 0;
  });
}

int EnumerateModelChoiceCommand(services::EnumerateRequest& request,
                                bool quiet,
                                const Session& session) {
  const std::vector<bool> temperatures = TemperatureSlotsOfConfig(request.config_path);
  return Guarded(session, quiet, temperatures, [&](SmcObserver* observer) {
    const auto announce = [&](const std::string& name) {
      if (session.primary() && !quiet) std::cerr << "model \"" << name << "\"\n";
    };
    const auto outcome = services::EnumerateModelChoice(request, observer, announce);
    if (outcome.interrupted) {
      std::cerr << "interrupted; the models enumerated so far are written\n";
      return kExitInterrupted;
    }
    PrintModelChoice(
        session, quiet, outcome, outcome.enumerations, [&](const services::EnumerateOutcome& e) {
          std::cout << "enumerated " << e.configurations << " configurations: " << e.accepted
                    << " accepted\nhistory: " << e.history_path << "\n";
          PrintAnswer(session, quiet, e.answer, e.strip);
        });
    return 0;
  });
}

}  // namespace combabc::cli
