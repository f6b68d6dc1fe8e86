#include "combabc/simulators/external_simulator.hpp"

#include <cstdio>

#include <cmath>
#include <utility>

namespace combabc {
namespace {

bool Mentions(const std::vector<std::string>& argv, const std::string& placeholder) {
  for (const std::string& a : argv) {
    if (a.find(placeholder) != std::string::npos) return true;
  }
  return false;
}

}  // namespace

bool ExternalSimulatorOptions::IsValid(SimulatorKind kind, std::string* why) const {
  ValidationError error;
  return ExplainValidation(IsValid(kind, &error), error, why);
}

bool ExternalSimulatorOptions::IsValid(SimulatorKind kind, ValidationError* error) const {
  // fail(field, constraint) or fail(field, value, constraint).
  auto fail = [&](const std::string& field, const std::string& value, const std::string& rest) {
    if (error) *error = {"ExternalSimulatorOptions", field, value, rest};
    return false;
  };
  auto refuse = [&](const std::string& field, const std::string& rest) {
    return fail(field, "", rest);
  };
  if (kind == SimulatorKind::kSensor) return refuse("kind", "is the built-in sensor, not external");
  if (argv.empty() || argv.front().empty()) return refuse("argv", "is empty; name the program");
  if (output_size < 1) return fail("output_size", std::to_string(output_size), "must be >= 1");
  if (!(timeout_s >= 0.0) || !std::isfinite(timeout_s)) return refuse("timeout_s", "must be >= 0");
  if (!(startup_timeout_s >= 0.0) || !std::isfinite(startup_timeout_s)) {
    return refuse("startup_timeout_s", "must be >= 0");
  }
  if (retries < 0) return fail("retries", std::to_string(retries), "must be >= 0");
  if (work_directory.empty()) return refuse("work_directory", "is empty");
  if (kind == SimulatorKind::kCommand) {
    if (params == Transport::kStdout) return refuse("params", "must be \"file\" or \"stdin\"");
    if (results == Transport::kStdin) return refuse("results", "must be \"stdout\" or \"file\"");
    if (params == Transport::kFile && !Mentions(argv, "{params}")) {
      return refuse("argv",
                    "has no {params}: with params = \"file\" the program must be told where");
    }
    if (results == Transport::kFile && !Mentions(argv, "{output}")) {
      return refuse("argv",
                    "has no {output}: with results = \"file\" the program must be told where");
    }
  } else if (Mentions(argv, "{params}") || Mentions(argv, "{output}")) {
    return refuse("argv", "of a worker cannot use {params} or {output} (requests come on stdin)");
  }
  return true;
}

std::vector<std::string> ExpandArgv(const std::vector<std::string>& argv,
                                    const std::string& params,
                                    const std::string& output,
                                    const std::string& workdir,
                                    const std::string& config_dir,
                                    const SimulatorExperiment* experiment) {
  std::vector<std::pair<std::string, std::string>> values = {
      {"{config_dir}", config_dir.empty() ? "." : config_dir},
      {"{workdir}", workdir},
      {"{params}", params},
      {"{output}", output},
  };
  if (experiment != nullptr) {
    const auto number = [](double x) {
      char b[40];
      std::snprintf(b, sizeof b, "%.17g", x);
      return std::string(b);
    };
    values.insert(values.end(),
                  {{"{experiment}", experiment->name},
                   {"{load_x}", number(experiment->load_x)},
                   {"{load_y_fraction}", number(experiment->load_y_fraction)},
                   {"{load_amplitude}", number(experiment->load_force)},
                   {"{frequency}", number(experiment->frequency_hz)}});
  }
  std::vector<std::string> out;
  out.reserve(argv.size());
  for (const std::string& a : argv) {
    // One left-to-right pass: a substituted value is never scanned again, so a path that itself
    // contains "{output}" arrives literally.
    std::string expanded;
    std::size_t i = 0;
    while (i < a.size()) {
      bool replaced = false;
      for (const auto& [name, value] : values) {
        if (a.compare(i, name.size(), name) == 0) {
          expanded += value;
          i += name.size();
          replaced = true;
          break;
        }
      }
      if (!replaced) expanded += a[i++];
    }
    out.push_back(std::move(expanded));
  }
  return out;
}

}  // namespace combabc
