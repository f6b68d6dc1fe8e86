#pragma once
// `combabc design CONFIG`: rank the candidate experiments of the config's [design] table by the
// information they are expected to add about the bits (design/experiment_design.hpp), from the
// prior or a finished run's posterior, and write the ranking, the greedy selection, each clamp's
// expected identifiability per candidate (CSV and a figure), and the campaign's next step: a
// complete next config (the experiments so far and the best candidate's) with plain instructions
// for the bench, or, when no candidate is expected to decide another clamp, the stop and why.
#include <string>
#include <vector>

#include "combabc/design/experiment_design.hpp"
#include "combabc/export/campaign.hpp"

namespace combabc::services {

struct DesignRequest {
  std::string config_path;
  std::string posterior_path;    // a run history whose last complete wave is what is known
  std::string output_directory;  // empty: design/ in the config's [output] directory
  int threads = -1;              // overrides [sampler] threads when >= 0
  bool overwrite = false;
  bool figure = true;  // identifiability.<fmt> through the Python script
};

struct DesignCandidate {
  double load_x = 0.0;  // m
  double load_y_fraction = 0.5;
  double scan_from = 0.0;  // m
  double scan_to = 0.0;    // m
  double scan_y_fraction = 0.5;
};

// A clamp the campaign leaves undecided, and why.
struct UndecidedClamp {
  int bit = 0;         // 0-based
  std::string where;   // "clamp 13 (edge 1, 60-65 cm)"
  std::string reason;  // "the response there is below the noise for every candidate", ...
};

struct DesignOutcome {
  std::string directory;
  std::string population;  // what was known: "the prior (every one of 64 configurations)", ...
  // How the predictions were made: "the population reweighted" or "the truths' neighbourhoods"
  // (--posterior: docs/algorithm.md, "Honest predictions"), and what that cost.
  std::string method;
  std::size_t simulated = 0;  // configurations simulated
  double simulate_seconds = 0.0;
  double noise_sigma = 0.0;  // [design] noise, of the normalised profile's peak
  double width = 0.0;        // the strip's (m): y fractions become mm from edge 1
  std::size_t particles = 0;
  bool exhaustive = false;  // the population is every configuration (no sampling error in it)
  // Configurations dropped because the plate cannot be solved in them (plate::SingularSystem),
  // and the first one's reason; `particles` counts those kept.
  std::size_t singular = 0;
  std::string singular_reason;
  std::vector<DesignCandidate> candidates;
  design::DesignResult result;
  // The campaign: clamps decided now (|P(fixed) - 0.5| > margin in what is known), the number the
  // best candidate is expected to leave decided, and whether to stop: every clamp decided, or no
  // candidate expected to decide another one (then `undecided` says which and why).
  int clamps = 0;
  int decided_now = 0;
  double expected_decided = 0.0;
  bool stop = false;
  std::string stop_reason;
  std::vector<UndecidedClamp> undecided;
  // Plain instructions for the best candidate (where the shaker goes, which line to scan, the
  // file to write and the command to run next); empty when stopping.
  std::vector<std::string> instructions;
  std::string next_config;       // next.toml: the config with every experiment, the new one last
  std::string next_config_path;  // where it was written
  std::string next_data_path;    // where the new experiment's data file is expected
  // The campaign view of the run (--posterior only; its `alone` empty otherwise): per clamp, its
  // P(fixed) in the run, and over the truths' neighbourhoods with all the run's experiments and
  // with each one's likelihood alone (docs/algorithm.md, "Which experiment decided which clamp").
  CampaignView campaign;
  double wall_seconds = 0.0;
};

// The experiments that decide clamp k (0-based) alone, on the run's side, joined by ", ";
// "together" where the run decides it and none alone does; "" where the run leaves it undecided.
inline std::string DecidedBy(const DesignOutcome& o, std::size_t k) {
  return CampaignDecidedBy(o.campaign, k);
}

DesignOutcome RunDesign(const DesignRequest& request);

}  // namespace combabc::services
