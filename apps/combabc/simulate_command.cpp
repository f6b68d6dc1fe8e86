// `combabc simulate`.
#include <iostream>
#include <memory>
#include <string>

#include "combabc/services/simulate.hpp"
#include "subcommands.hpp"

namespace combabc::cli {
namespace {

struct SimulateArgs {
  std::string config;
  std::string clamps;
  std::string output = "profile.csv";
  bool overwrite = false;
  bool low_fidelity = false;
};

int SimulateCommand(const SimulateArgs& args, const Session& session) {
  return PrimaryOnly(session, [&] {
    services::SimulateConfiguration(
        args.config, args.clamps, args.output, args.overwrite, args.low_fidelity);
    std::cout << "wrote " << args.output << "\n";
    return 0;
  });
}

}  // namespace

Command AddSimulateCommand(CLI::App& app) {
  auto args = std::make_shared<SimulateArgs>();
  auto* simulate = app.add_subcommand("simulate", "Simulate one bit (clamp) configuration to CSV");
  simulate->add_option("CONFIG", args->config, "Config file (its simulator is used)")->required();
  simulate
      ->add_option("--clamps",
                   args->clamps,
                   "One 0/1 per bit (the sensor: per clamp, 1 = fixed), e.g. 0110...")
      ->required();
  simulate->add_option("-o,--output", args->output, "CSV to write (default profile.csv)");
  simulate->add_flag("--overwrite", args->overwrite, "Replace an existing CSV at that path");
  simulate->add_flag("--low-fidelity",
                     args->low_fidelity,
                     "Simulate the cheap model of [simulator.low_fidelity] instead, at the "
                     "expensive simulator's output coordinates");
  AddNoCacheFlag(*simulate);
  return {simulate, [args](const Session& session) { return SimulateCommand(*args, session); }};
}

}  // namespace combabc::cli
