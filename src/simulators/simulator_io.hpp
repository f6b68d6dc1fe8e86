#pragma once
// The text formats of the external simulators (docs/simulators.md): a candidate as JSON, CSV or
// one worker request line, and the outputs read back from CSV, JSON or a worker response. The
// readers return an empty string on success, else the reason a SimulationFailed carries, naming
// the line.
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "combabc/params/parameter_value.hpp"
#include "combabc/simulators/external_simulator.hpp"

namespace combabc::simulators_internal {

// {"bits": [0, 1, ...], "reals": {"name": value, ...}}
std::string ParamsJson(const ParameterView& theta, const std::vector<std::string>& real_names);
// "name,value" then one row per bit (by bit name) and per real.
std::string ParamsCsv(const ParameterView& theta,
                      const std::vector<std::string>& bit_names,
                      const std::vector<std::string>& real_names);
// "<bits as 0/1 characters> <real> ...\n" (protocol combabc-worker 1).
std::string RequestLine(const ParameterView& theta);

// Numbers separated by commas, whitespace or line breaks (CSV), or one JSON array of numbers.
std::string ReadValues(std::string_view text, DataFormat format, std::span<double> out);
// "ok v1 ... vN" or "error <reason>".
std::string ReadResponse(std::string_view line, std::span<double> out);

// Double with 17 significant digits: what the program reads is exactly the candidate's value.
std::string Number(double x);

}  // namespace combabc::simulators_internal
