#pragma once
// `combabc run` and `combabc enumerate` on a config with [model_choice]: each model in turn, then
// the model probabilities, then each model's answer (docs/config.md, "Model choice").
#include "combabc/services/enumerate.hpp"
#include "combabc/services/run.hpp"
#include "command.hpp"

namespace combabc::cli {

// Whether the config asks for a model choice; false when it cannot be read (the job then says
// why).
bool IsModelChoiceConfig(const std::string& config_path);

int RunModelChoiceCommand(services::RunRequest& request, bool quiet, const Session& session);
int EnumerateModelChoiceCommand(services::EnumerateRequest& request,
                                bool quiet,
                                const Session& session);

}  // namespace combabc::cli
