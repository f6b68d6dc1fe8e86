#pragma once
// `combabc design CONFIG`: rank the candidate experiments of the config's [design] table by the
// information they are expected to add about the bits (design/experiment_design.hpp), from the
// prior or a finished run's posterior, and write the ranking, the greedy selection, each clamp's
// expected identifiability per candidate (CSV and a figure) and a ready [[experiment]] block for
// the best next experiment.
#include <string>
#include <vector>

#include "combabc/design/experiment_design.hpp"

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

struct DesignOutcome {
  std::string directory;
  std::string population;  // what was known: "the prior (every one of 64 configurations)", ...
  std::size_t particles = 0;
  bool exhaustive = false;  // the population is every configuration (no sampling error in it)
  // Configurations dropped because the plate cannot be solved in them (plate::SingularSystem),
  // and the first one's reason; `particles` counts those kept.
  std::size_t singular = 0;
  std::string singular_reason;
  std::vector<DesignCandidate> candidates;
  design::DesignResult result;
  double noise_sigma = 0.0;     // [design] noise: per point, as a fraction of the profile's peak
  std::string next_experiment;  // the [[experiment]] block for the best candidate
  double wall_seconds = 0.0;
};

DesignOutcome RunDesign(const DesignRequest& request);

}  // namespace combabc::services
