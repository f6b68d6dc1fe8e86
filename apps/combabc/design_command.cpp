// `combabc design`.
#include <algorithm>
#include <cstdio>
#include <limits>
#include <memory>
#include <vector>

#include "combabc/services/design.hpp"
#include "subcommands.hpp"

namespace combabc::cli {
namespace {

struct DesignArgs {
  services::DesignRequest request;
  bool no_figure = false;
};

// The ranking (best ten), the greedy selection and where the files are.
void PrintDesign(const services::DesignOutcome& o) {
  const auto& r = o.result;
  std::printf("design from %s; %zu candidates, noise sigma %.3g on the normalised profile\n",
              o.population.c_str(),
              o.candidates.size(),
              o.noise_sigma);
  if (o.singular > 0) {
    // Dropped, as a run fails them: the ranking is over the configurations the plate can be
    // solved in.
    std::printf(
        "note: %zu of the %zu configurations left out, the plate being singular in them "
        "(the first: %s)\n",
        o.singular,
        o.singular + o.particles,
        o.singular_reason.c_str());
  }
  std::printf("prior: %.2f bits of marginal entropy, %.0f clamps identified\n",
              r.prior_entropy,
              r.prior_identified);
  std::vector<std::size_t> order(o.candidates.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return r.scores[a].information_gain > r.scores[b].information_gain;
  });
  std::printf(
      "rank  load x cm  load y  scan cm     line   gain bits (se)   identified  wrong    ess\n");
  for (std::size_t rank = 0; rank < std::min<std::size_t>(10, order.size()); ++rank) {
    const auto& c = o.candidates[order[rank]];
    const auto& s = r.scores[order[rank]];
    std::printf("%4zu  %9.1f  %6.2f  %5.1f-%-5.1f %5.2f  %6.2f (%.2f)    %10.1f  %5.1f  %5.0f\n",
                rank + 1,
                c.load_x * 100,
                c.load_y_fraction,
                c.scan_from * 100,
                c.scan_to * 100,
                c.scan_y_fraction,
                s.information_gain,
                s.information_gain_se,
                s.identified,
                s.wrong,
                s.effective_particles);
  }
  std::printf("greedy selection:\n");
  for (std::size_t step = 0; step < r.selected.size(); ++step) {
    const auto& c = o.candidates[static_cast<std::size_t>(r.selected[step])];
    const auto& s = r.cumulative[step];
    std::printf(
        "  %zu. load %.1f cm (y %.2f), scan %.1f-%.1f cm (y %.2f): %.2f bits in all, "
        "%.1f clamps identified, %.1f wrong\n",
        step + 1,
        c.load_x * 100,
        c.load_y_fraction,
        c.scan_from * 100,
        c.scan_to * 100,
        c.scan_y_fraction,
        s.information_gain,
        s.identified,
        s.wrong);
  }
  double least = std::numeric_limits<double>::infinity();
  for (const auto& s : r.cumulative) least = std::min(least, s.effective_particles);
  if (!o.exhaustive && least < 20) {
    std::printf(
        "note: the reweighted population falls to %.0f effective particles: the gains and "
        "identified counts are upper bounds (a larger population: more accepted "
        "particles, or [design] particles)\n",
        least);
  }
  std::printf("design: %s (%.2f s; next experiment: %s/next_experiment.toml)\n",
              o.directory.c_str(),
              o.wall_seconds,
              o.directory.c_str());
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
