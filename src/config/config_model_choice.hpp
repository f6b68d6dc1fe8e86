#pragma once
// Private to config parsing: [model_choice] (config_model_choice.cpp).
#include <string>
#include <string_view>

#include <toml++/toml.h>

#include "config_reader.hpp"

namespace combabc {
struct CalibrationConfig;
}  // namespace combabc

namespace combabc::config_internal {

// Reads [model_choice] (names, priors, reference) into config->model_choice; the models' configs
// are built once the file's own config is known to be valid (BuildCandidateConfigs).
void ParseModelChoice(TableReader& root, CalibrationConfig* config);
// Builds and checks each candidate model's config (CandidateModel::config_text), refusing a bad
// key at its own line, a cheap simulator, and models whose outputs differ.
void BuildCandidateConfigs(CalibrationConfig* config);
// ParseConfig on a parsed table (config.cpp): `text` is kept as the config's text.
CalibrationConfig ParseConfigTable(const toml::table& table,
                                   std::string_view text,
                                   const std::string& path);

}  // namespace combabc::config_internal
