#pragma once
// The campaign step of `combabc design` (docs/algorithm.md, "Designing the next experiment"): the
// next config (every experiment so far, the single-experiment shorthand converted to an
// [[experiment]] table, and the chosen candidate's, with the data file it expects), the plain
// instructions for the bench, and where each clamp is. Private to src/services.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "combabc/config/config.hpp"
#include "combabc/export/campaign.hpp"
#include "combabc/services/design.hpp"

namespace combabc::services {

struct NextStep {
  std::string config_text;       // next.toml
  std::string experiment_name;   // the new [[experiment]]'s name
  std::string data_path;         // where its data file is expected (absolute)
  std::string output_directory;  // the next run's output directory (absolute)
};

// The next config for candidate `k`, to be written as `design_directory`/next.toml: `c`'s text
// with its data paths and output directory rebased there, the shorthand converted, and the new
// experiment appended. Its data file is expected beside the run's output directory (where the
// campaign's files are); the next run writes to a sibling of that directory, "<name>-e<N>" for N
// experiments. Throws combabc::Error(kUsage) where the config's text cannot be converted.
NextStep WriteNextConfig(const CalibrationConfig& c,
                         const DesignCandidate& k,
                         const std::filesystem::path& design_directory);

// "clamp 13 (edge 1, 60-65 cm)": clamp k (0-based) of the sensor; edge 1 is y = 0.
std::string ClampWhere(const CalibrationConfig& c, int bit);

// The plain instructions for the bench: where the shaker goes (cm along the strip, mm from edge 1),
// which line to scan (mm from edge 1), from where to where at what spacing, the file to write (its
// columns and units) and the command to run next.
std::vector<std::string> Instructions(const CalibrationConfig& c,
                                      const DesignCandidate& k,
                                      const NextStep& next,
                                      const std::string& next_config_path);

// The campaign view of a finished joint run of the sensor (docs/algorithm.md, "Which experiment
// decided which clamp"), as `combabc design --posterior` computes it: from the run's config (the
// history's copy) and its data files, with its [design]'s truths and identified_margin, or their
// defaults without one; its own simulations of the truths' neighbourhoods. For `combabc export`
// and the report. nullopt for a run with one experiment or another simulator (nothing to say);
// also where it cannot be computed (the data files gone, continuous parameters, signed
// multi-fidelity weights), then with why in *why_not: an export goes on without it.
std::optional<CampaignView> RunCampaignView(const std::string& history_path, std::string* why_not);

}  // namespace combabc::services
