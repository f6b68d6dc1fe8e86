#pragma once
// The text formats of the external simulators (docs/simulators.md): a candidate as JSON, CSV or
// one worker request line, and the outputs read back from CSV, JSON or a worker response. The
// readers return an empty string on success, else the reason a SimulationFailed carries, naming
// the line.
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "combabc/params/parameter_value.hpp"
#include "combabc/simulators/external_simulator.hpp"

namespace combabc::simulators_internal {

// {"bits": [0, 1, ...], "reals": {"name": value, ...}}, and with an experiment
// "experiment": {"name": ..., "load_x": ..., "load_y_fraction": ..., "load_amplitude": ...,
// "frequency": ...}.
std::string ParamsJson(const ParameterView& theta,
                       const std::vector<std::string>& real_names,
                       const SimulatorExperiment* experiment = nullptr);
// "name,value" then one row per bit (by bit name) and per real, and with an experiment the rows
// experiment, load_x, load_y_fraction, load_amplitude and frequency.
std::string ParamsCsv(const ParameterView& theta,
                      const std::vector<std::string>& bit_names,
                      const std::vector<std::string>& real_names,
                      const SimulatorExperiment* experiment = nullptr);
// "<id> <bits as 0/1 characters> <real> ...\n" (protocol combabc-worker 2): id numbers the
// worker's requests 1, 2, ...
std::string RequestLine(std::uint64_t id, const ParameterView& theta);

// Numbers separated by commas, whitespace or line breaks (CSV), or one JSON array of numbers.
std::string ReadValues(std::string_view text, DataFormat format, std::span<double> out);
// The answer to request `id`: "<id> ok v1 ... vN" or "<id> error <reason>". *in_step: the line
// answers request `id` with "ok" or "error", so the worker is still in step with the protocol
// even when its values were refused (wrong count, NaN); a line with another id (an answer
// repeated, skipped or out of order) or no "ok"/"error" leaves it out of step.
std::string ReadResponse(std::string_view line,
                         std::uint64_t id,
                         std::span<double> out,
                         bool* in_step);

// Double with 17 significant digits: what the program reads is exactly the candidate's value.
std::string Number(double x);

}  // namespace combabc::simulators_internal
