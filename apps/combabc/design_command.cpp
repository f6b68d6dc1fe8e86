// `combabc design`.
#include <algorithm>
#include <cstdio>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "combabc/services/design.hpp"
#include "subcommands.hpp"

namespace combabc::cli {
namespace {

struct DesignArgs {
  services::DesignRequest request;
  bool no_figure = false;
};

// The ten candidates of most information gain, best first.
void PrintRanking(const services::DesignOutcome& o) {
  const auto& r = o.result;
  // Across the strip: mm from edge 1 (y = 0, clamps 1 to n), as the bench measures it.
  std::printf(
      "rank  load cm  load mm  scan cm      line mm  gain bits (se)  identified  wrong    ess\n");
  std::vector<std::size_t> order(o.candidates.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return r.scores[a].information_gain > r.scores[b].information_gain;
  });
  for (std::size_t rank = 0; rank < std::min<std::size_t>(10, order.size()); ++rank) {
    const auto& c = o.candidates[order[rank]];
    const auto& s = r.scores[order[rank]];
    std::printf("%4zu  %7.1f  %7.1f  %5.1f-%-5.1f  %7.1f  %6.2f (%.2f)   %10.1f  %5.1f  %5.0f\n",
                rank + 1,
                c.load_x * 100,
                c.load_y_fraction * o.width * 1000,
                c.scan_from * 100,
                c.scan_to * 100,
                c.scan_y_fraction * o.width * 1000,
                s.information_gain,
                s.information_gain_se,
                s.identified,
                s.wrong,
                s.effective_particles);
  }
}

// The ranking (best ten), the greedy selection, where the campaign stands and what to do next.
void PrintDesign(const services::DesignOutcome& o) {
  const auto& r = o.result;
  std::printf("design from %s; %zu candidates, noise sigma %.3g of the normalised profile's peak\n",
              o.population.c_str(),
              o.candidates.size(),
              o.noise_sigma);
  std::printf("predictions from %s: %zu configurations simulated in %.1f s\n",
              o.method.c_str(),
              o.simulated,
              o.simulate_seconds);
  if (o.singular > 0) {
    // Dropped, as a run fails them: the ranking is over the configurations the plate can be
    // solved in.
    std::printf(
        "note: %zu of the %zu configurations left out, the plate being singular in them "
        "(the first: %s)\n",
        o.singular,
        o.simulated,
        o.singular_reason.c_str());
  }
  PrintRanking(o);
  std::printf("greedy selection (mm from edge 1):\n");
  for (std::size_t step = 0; step < r.selected.size(); ++step) {
    const auto& c = o.candidates[static_cast<std::size_t>(r.selected[step])];
    const auto& s = r.cumulative[step];
    std::printf(
        "  %zu. load %.1f cm, %.1f mm; scan %.1f-%.1f cm on the line at %.1f mm: %.2f bits in "
        "all, %.1f clamps identified, %.1f wrong\n",
        step + 1,
        c.load_x * 100,
        c.load_y_fraction * o.width * 1000,
        c.scan_from * 100,
        c.scan_to * 100,
        c.scan_y_fraction * o.width * 1000,
        s.information_gain,
        s.identified,
        s.wrong);
  }
  double least = std::numeric_limits<double>::infinity();
  for (const auto& s : r.cumulative) least = std::min(least, s.effective_particles);
  if (o.method.rfind("the prior draws", 0) == 0 && least < 20) {
    std::printf(
        "note: the reweighted population falls to %.0f effective particles: the gains and "
        "identified counts are upper bounds (more draws: [design] particles)\n",
        least);
  }
  // The campaign view: which experiment decided which clamp (campaign.csv has the numbers).
  if (!o.campaign.alone.empty()) {
    std::printf(
        "decided by (P(fixed) with each experiment alone, the other clamps at the run's values; "
        "campaign.csv):\n");
    std::vector<std::string> by(o.campaign.alone.size() + 1);
    for (std::size_t k = 0; k < o.campaign.run_p_fixed.size(); ++k) {
      const std::string who = services::DecidedBy(o, k);
      for (std::size_t e = 0; e < o.campaign.alone.size(); ++e) {
        if (who.empty() || who == "together") continue;
        // Names are [A-Za-z0-9_.-]: ", " separates them.
        const std::string& name = o.campaign.alone[e].name;
        if ((", " + who + ", ").find(", " + name + ", ") == std::string::npos) continue;
        by[e] += (by[e].empty() ? "" : ", ") + std::to_string(k + 1);
      }
      if (who == "together") by.back() += (by.back().empty() ? "" : ", ") + std::to_string(k + 1);
    }
    for (std::size_t e = 0; e < o.campaign.alone.size(); ++e) {
      std::printf("  %s alone: clamps %s\n",
                  o.campaign.alone[e].name.c_str(),
                  by[e].empty() ? "none" : by[e].c_str());
    }
    if (!by.back().empty()) std::printf("  only together: clamps %s\n", by.back().c_str());
  }
  std::printf("now: %d of %d clamps decided; with the best candidate: %.1f expected\n",
              o.decided_now,
              o.clamps,
              o.expected_decided);
  if (o.stop) {
    std::printf("stop: %s.\n", o.stop_reason.c_str());
  } else {
    std::printf("next experiment:\n");
    for (const std::string& line : o.instructions) std::printf("  %s\n", line.c_str());
  }
  // The undecided clamps: by number while the campaign goes on; when it stops, where each is and
  // why no candidate decides it, grouped by reason.
  if (!o.stop && !o.undecided.empty()) {
    std::string clamps;
    for (const auto& u : o.undecided) {
      clamps += (clamps.empty() ? "" : ", ") + std::to_string(u.bit + 1);
    }
    std::printf("undecided now: clamps %s\n", clamps.c_str());
  }
  std::vector<std::pair<std::string, std::string>> groups;  // reason, clamps
  for (const auto& u : o.undecided) {
    if (!o.stop) break;
    auto it = std::find_if(
        groups.begin(), groups.end(), [&](const auto& g) { return g.first == u.reason; });
    if (it == groups.end()) it = groups.insert(groups.end(), {u.reason, ""});
    it->second += (it->second.empty() ? "" : ", ") + u.where;
  }
  for (const auto& [reason, clamps] : groups) {
    std::printf("undecided: %s: %s\n", clamps.c_str(), reason.c_str());
  }
  std::printf("design: %s (%.2f s)\n", o.directory.c_str(), o.wall_seconds);
}

int DesignCommand(DesignArgs& args, const Session& session) {
  return PrimaryOnly(session, [&] {
    args.request.figure = !args.no_figure;
    PrintDesign(services::RunDesign(args.request));
    return 0;
  });
}

}  // namespace

Command AddDesignCommand(CLI::App& app) {
  auto args = std::make_shared<DesignArgs>();
  services::DesignRequest& request = args->request;
  auto* design = app.add_subcommand(
      "design", "Rank candidate experiments ([design]) by the information they would add");
  design->add_option("CONFIG", request.config_path, "Config file with a [design] table")
      ->required();
  design->add_option("--posterior",
                     request.posterior_path,
                     "A finished run's history: start from its posterior (default: the prior)");
  design->add_option(
      "-o,--output", request.output_directory, "Directory (default: design/ in [output])");
  design->add_option("-j,--threads", request.threads, "Threads, 0 = all cores")
      ->check(CLI::Range(0, kMaxThreads));
  design->add_flag("--overwrite", request.overwrite, "Write into an existing directory");
  design->add_flag("--no-figure", args->no_figure, "Skip identifiability.<fmt> (needs matplotlib)");
  AddNoCacheFlag(*design);
  return {design, [args](const Session& session) { return DesignCommand(*args, session); }};
}

}  // namespace combabc::cli
