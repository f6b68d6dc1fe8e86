#pragma once
// The campaign view of a joint run (docs/algorithm.md, "Which experiment decided which clamp"):
// per clamp, its P(fixed) in the run, over the truths' neighbourhoods with all the experiments
// together and with each experiment's likelihood alone, and which experiments decide it. The
// services layer computes it (services/design.cpp); `combabc design --posterior` and
// `combabc export` write it as campaign.csv (WriteCampaignCsv, one format for both), and the
// report draws its section from that file.
#include <cstddef>
#include <ostream>
#include <string>
#include <vector>

namespace combabc {

struct CampaignView {
  std::vector<std::string> clamp_names;  // per clamp (the run's bit names)
  int clamps_per_edge = 0;               // clamp k (from 1) is on edge 1 for k <= this
  double length_m = 0.0;                 // the strip's: each edge splits it into equal sections
  double identified_margin = 0.4;        // |P(fixed) - 0.5| above it decides a clamp
  std::vector<double> run_p_fixed;       // per clamp, in the run's posterior
  std::vector<double> together;          // per clamp, every experiment's likelihood
  struct Evidence {
    std::string name;             // the experiment's, "experiment 1" for the shorthand's
    std::vector<double> p_fixed;  // per clamp, its likelihood alone
  };
  std::vector<Evidence> alone;  // per experiment, in config order; empty: no view
};

// The experiments that decide clamp k (0-based) alone, on the run's side, joined by ", ";
// "together" where the run decides it and none alone does; "" where the run leaves it undecided.
std::string CampaignDecidedBy(const CampaignView& view, std::size_t k);

// campaign.csv (docs/history.md, "Export"): clamp, name, edge, from_cm, to_cm, p_fixed_run,
// p_fixed_together, one p_fixed_alone:<experiment> per experiment, decided_by.
void WriteCampaignCsv(std::ostream& out, const CampaignView& view);

}  // namespace combabc
