#pragma once
// Private helper for config parsing: typed access to one TOML table that records which keys were
// read, so that Finish() can reject every key nobody asked for (typos must not be silently
// ignored), and that formats errors as "file:line: dotted.key: message".
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <toml++/toml.h>

#include "combabc/core/enum_names.hpp"
#include "combabc/core/error.hpp"
#include "combabc/core/validation_error.hpp"

namespace combabc::config_internal {

// The widest range a key may take where only the sign or finiteness is checked.
inline constexpr double kHuge = std::numeric_limits<double>::max();

// "\"a\", \"b\"" for messages listing the allowed values.
std::string OneOf(std::initializer_list<const char*> names);

class TableReader {
 public:
  // prefix: the table's dotted name ("" for the root, "metric.component[0]", ...).
  TableReader(const toml::table& table, std::string prefix, const std::string& path);

  const std::string& path() const { return *path_; }
  const std::string& prefix() const { return prefix_; }
  int line() const;
  // Dotted name of a key of this table.
  std::string Key(std::string_view key) const;
  // Line of the key's value, or of the table if the key is absent.
  int Line(std::string_view key) const;
  bool Has(std::string_view key) const;

  // Throws combabc::Error(kConfig) at the key's line (the table's if the key is absent).
  [[noreturn]] void Fail(std::string_view key, const std::string& message) const;
  // Throws at a node's line with an explicit dotted name (array elements).
  [[noreturn]] void FailAt(const toml::node& node,
                           const std::string& dotted,
                           const std::string& message) const;

  // Typed getters: nullopt if the key is absent; a type mismatch throws. Each marks the key read.
  std::optional<bool> Bool(std::string_view key);
  std::optional<std::string> String(std::string_view key);
  std::optional<double> Number(std::string_view key);  // integer or float; NaN rejected
  std::optional<std::int64_t> Integer(std::string_view key);
  std::optional<std::vector<double>> Numbers(std::string_view key);
  std::optional<std::vector<std::string>> Strings(std::string_view key);
  // Nested table (inline or [section]); nullopt if absent.
  std::optional<TableReader> Table(std::string_view key);
  // Array of tables ([[key]]); empty if absent.
  std::vector<TableReader> Tables(std::string_view key);
  // Raw node for shapes the getters do not cover (marks the key read); nullptr if absent.
  const toml::node* Raw(std::string_view key);

  // A string naming one of an enum's values (core/enum_names.hpp): nullopt if absent; an unknown
  // value throws 'unknown <what> "text"; expected one of "a", "b"' from the enum's own table.
  template <NamedEnum T>
  std::optional<T> Choice(std::string_view key, const char* what) {
    const auto text = String(key);
    if (!text) return std::nullopt;
    const std::optional<T> value = ParseEnum<T>(*text);
    if (!value) {
      Fail(key,
           "unknown " + std::string(what) + " " + Excerpt(*text) + "; expected one of " +
               EnumChoices<T>());
    }
    return value;
  }

  // Range helpers: value within [lo, hi] or throw naming the key.
  double NumberIn(std::string_view key, double fallback, double lo, double hi);
  int IntegerIn(std::string_view key, int fallback, std::int64_t lo, std::int64_t hi);

  // Rejects keys that were never read.
  void Finish() const;

 private:
  const toml::node* Get(std::string_view key);

  const toml::table* table_;
  std::string prefix_;
  const std::string* path_;
  std::vector<std::string> read_;   // keys present and read
  std::vector<std::string> asked_;  // every key a getter asked for: the table's vocabulary
};

const char* TypeName(const toml::node& node);
int LineOf(const toml::node& node);

}  // namespace combabc::config_internal

#include "combabc/data/measured_data.hpp"
#include "combabc/plate/sensor_model.hpp"

namespace combabc {
struct CalibrationConfig;
struct MetricConfig;
}  // namespace combabc

namespace combabc::config_internal {

// Where a field of SmcOptions / BinarySpaceOptions / SensorOptions was set, so that a failed
// IsValid() is reported at the config key the user wrote rather than at the C++ field.
struct Source {
  std::string key;
  int line = 0;
};

struct Sources {
  std::map<std::string, Source> smc;     // SmcOptions field ("num_waves", "tempering") -> key
  std::map<std::string, Source> space;   // BinarySpaceOptions field -> key
  Source sampler;                        // fallback: the [sampler] table
  std::optional<Source> multi_fidelity;  // the [sampler.multi_fidelity] table, when given
  std::optional<Source> method;          // sampler.method, when given
  std::optional<Source> moves;           // the [sampler.moves] table, when given
};

// Records that `field` was set by key `key` of `t` (if present).
void Note(std::map<std::string, Source>& map,
          const std::string& field,
          const TableReader& t,
          std::string_view key);
// [from, to] in the data's position unit (from < to, finite), returned in metres.
std::pair<double, double> WindowKey(TableReader& t, std::string_view key, double metres_per_unit);

// Section parsers, each reading its table of `root` into `config` (and calling Finish on it).
// [model] (config_model.cpp): the sensor's options (defaults when the table is absent);
// model_sources: where each SensorOptions field was set.
void ParseModelSection(TableReader& root,
                       CalibrationConfig* config,
                       std::map<std::string, Source>* model_sources);
// A load table ([model.load], [experiment.load]) and an output table ([model.output],
// [experiment.output]) over a load case that holds the defaults (config_model.cpp).
void ParseLoadTable(TableReader& l,
                    plate::LoadCase* load_case,
                    double* frequency_hz,
                    std::map<std::string, Source>* sources);
void ParseOutputTable(TableReader& o,
                      double length,
                      plate::LoadCase* load_case,
                      std::map<std::string, Source>* sources);
// Reports a failed SensorOptions::IsValid at the config key that set the field (sources), or
// the key that would set it, at `fallback_line` (config_model.cpp).
[[noreturn]] void ThrowModelError(const ValidationError& error,
                                  const std::map<std::string, Source>& sources,
                                  int fallback_line,
                                  const std::string& path);
// [[experiment]] tables, or the shorthand [data] and [metric] (config_experiment.cpp): after
// [model], [simulator] and [sampler]; sets config->experiments, the simulator's concatenated
// outputs and the sampler's threshold schedules.
void ParseExperiments(TableReader& root,
                      CalibrationConfig* config,
                      const std::map<std::string, Source>& model_sources);
// [simulator] (config_simulator.cpp): after [model]; sets the simulator's outputs and the bit
// names (config->space.names).
void ParseSimulatorSection(TableReader& root, CalibrationConfig* config);
// [simulator.low_fidelity] (config_simulator.cpp): after the experiments and [parameters]; sets
// config->low_fidelity (its outputs mapped onto the expensive simulator's).
void ParseLowFidelitySection(TableReader& root, CalibrationConfig* config);
// Refuses an argv that uses an experiment placeholder ({experiment}, ...) where the config has no
// [[experiment]] tables (config_experiment.cpp); key: the argv key, at `line`.
void RefuseExperimentPlaceholders(const std::vector<std::string>& argv,
                                  int line,
                                  const std::string& key,
                                  const std::string& path);
// [sampler] (config_sampler.cpp): needs the bit names (config->space.names) for prior arrays
// and tie numbers.
void ParseSamplerSection(TableReader& root, CalibrationConfig* config, Sources* sources);
// [proposal] and [parameters.<name>] (config_proposal.cpp).
void ParseProposalSection(TableReader& root, CalibrationConfig* config);
void ParseParametersSection(TableReader& root, CalibrationConfig* config);
void ParseJointPriorSection(TableReader& root, CalibrationConfig* config);
// [design] (config_design.cpp): after [model].
void ParseDesignSection(TableReader& root,
                        CalibrationConfig* config,
                        const std::map<std::string, Source>& model_sources);
// A [data] table (config_experiment.cpp); impact_default: the Gaussian extension's default
// centre (the experiment's load position), nullopt where there is none (external simulators).
void ParseDataTable(TableReader& t, std::optional<double> impact_default, DataConfig* data);
// A [metric] table (config_metric.cpp), with windows in `position_unit` and schedules of
// `num_waves` waves.
void ParseMetricTable(TableReader& t,
                      LengthUnit position_unit,
                      int num_waves,
                      MetricConfig* metric);

}  // namespace combabc::config_internal
