#pragma once
// The TOML configuration of a whole calibration run (docs/config.md lists every key): the sensor
// model, the measured data, the metric (paper Eqs. 4-7), the sampler and the outputs.
//
// Every problem in the file -- malformed TOML, an unknown key (in any table), a value of the
// wrong type or out of range, an inconsistency such as a list threshold with the wrong number of
// waves -- is thrown as combabc::Error(ErrorKind::kConfig) whose what() reads
// "file:line: dotted.key: message", so the CLI can print it as is and exit with 78.
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "combabc/config/model_choice_config.hpp"
#include "combabc/data/measured_data.hpp"
#include "combabc/metrics/metric_component.hpp"
#include "combabc/params/binary_space.hpp"
#include "combabc/params/continuous_prior.hpp"
#include "combabc/params/joint_prior.hpp"
#include "combabc/plate/sensor_model.hpp"
#include "combabc/samplers/smc_options.hpp"
#include "combabc/simulators/external_simulator.hpp"

namespace combabc {

// The folder inside OutputConfig::directory where `combabc enumerate` writes its history, tables
// and report, apart from the run's (services/enumerate.cpp).
inline constexpr const char* kEnumerationFolder = "enumeration";

struct OutputConfig {
  // Where the run writes; relative paths are resolved against the config file's directory.
  std::string directory = "results";
  std::string database = "history.sqlite";            // file name inside `directory`
  std::vector<std::string> figure_formats = {"png"};  // each "png", "svg" or "pdf"
  // Keep each accepted particle's simulated curve Y* in the history (SmcOptions::keep_outputs).
  bool keep_simulated_curves = true;
};

struct MetricConfig {
  // The preset named in the file, if any (its components are expanded into `components`).
  std::optional<MetricPreset> preset;
  // In distance-vector order; windows in metres.
  std::vector<MetricComponentConfig> components;
};

// [simulator]: the simulator the run calibrates and what it declares. Every kind declares its
// outputs; the workflow (data, metric windows, history, report) sees only this declaration.
struct SimulatorConfig {
  SimulatorKind kind = SimulatorKind::kSensor;
  // The sensor: its [model.output] positions; command / worker: [simulator.outputs].
  SimulatorOutputs outputs;
  // Command / worker only. work_directory is the run's (set when the run starts: "." here).
  ExternalSimulatorOptions external;
  int argv_line = 0;  // the line of simulator.argv, for errors found when the program is started
};

// [simulator.low_fidelity] (docs/config.md, "Multi-fidelity"): the cheap simulator of a
// multi-fidelity run (SmcProblem::low_fidelity). It takes the run's bits (the same count) and
// reals (by name); its outputs stand for the expensive simulator's by coordinate.
struct LowFidelityConfig {
  // Its kind and, for command / worker, its program and [simulator.low_fidelity.outputs] (the
  // coordinates of one experiment, as [simulator.outputs]).
  SimulatorConfig simulator;
  // kind = "sensor": [model] with [simulator.low_fidelity.model] over it. It simulates the run's
  // experiments (their loads) at the expensive simulator's output coordinates.
  plate::SensorOptions model;
  // For each output of the expensive simulator, in order, the cheap simulator's output at the
  // same coordinate (within 1e-9 m) of the same experiment; the cheap one's others are dropped.
  std::vector<int> output_map;
  int line = 0;  // the [simulator.low_fidelity] table's line
};

// One experiment (docs/config.md, "Experiments"): a load and scan of the sensor, its measured data
// and its metric. A config's [[experiment]] tables list several; the single-experiment keys
// ([model.load], [model.output], [data], [metric]) are the shorthand for one, named "". The bits
// and reals are shared: one candidate is simulated for every experiment, and its distance vector
// is the experiments' components one after the other.
struct ExperimentConfig {
  std::string name;  // "" for the shorthand's one experiment; else unique, [A-Za-z0-9_.-]+
  int line = 0;      // its [[experiment]] header (0 for the shorthand)
  // The sensor's load and scan line (its outputs), and the drive frequency (Hz). An external
  // simulator receives them with each request (docs/simulators.md).
  plate::LoadCase load;
  double frequency_hz = 5.0;
  // The coordinates of this experiment's outputs: the sensor's load.output_positions, or an
  // external simulator's [simulator.outputs].
  std::vector<double> output_coordinates;
  DataConfig data;
  MetricConfig metric;

  // "name/" before each component's name in the distance vector ("" for the shorthand).
  std::string ComponentPrefix() const { return name.empty() ? "" : name + "/"; }
  // The config key of one of its tables: "data" for the shorthand, "experiment[2].data" else.
  std::string Key(std::size_t index, const std::string& table) const;
};

// [design] (docs/config.md, "Design"): the candidate experiments `combabc design` ranks, the
// product of the grids below (positions in metres here).
struct DesignConfig {
  std::vector<double> load_x;                    // along the sensor
  std::vector<double> load_y_fraction = {0.5};   // across the width
  std::vector<std::pair<double, double>> scans;  // scan windows [from, to]
  std::vector<double> scan_y_fraction = {0.5};   // scan lines across the width
  double scan_spacing = 0.01;                    // between scan points
  double noise = 0.01;                           // measurement noise sigma, of the peak
  int truths = 200;                              // plausible truths per candidate
  int particles = 2000;                          // prior draws (when no posterior is given)
  int select = 3;                                // experiments chosen greedily
  double identified_margin = 0.4;                // |P(fixed) - 0.5| above it: identified
  int line = 0;                                  // the [design] table's line
};

struct CalibrationConfig {
  std::string path;         // the config file as given ("<string>" for ParseConfig without a file)
  std::string directory;    // its directory: data.csv and output.directory are relative to it
  std::string text;         // the TOML text verbatim (provenance for the run history)
  std::string description;  // free text, top-level `description`

  SimulatorConfig simulator;
  // A multi-fidelity run's cheap simulator; its options are smc.multi_fidelity
  // ([sampler.multi_fidelity]).
  std::optional<LowFidelityConfig> low_fidelity;
  // The sensor simulator, from [model] (kind = "sensor" only); every key not given keeps
  // SensorOptions' default, and model.normalise mirrors data.normalise so Y and Y* are scaled
  // alike. Its one load case and frequency are [model.load] and [model.output]: the shorthand
  // experiment's, and every [[experiment]]'s defaults (SensorModels() gives the models a run
  // builds).
  plate::SensorOptions model;
  // The experiments, in the order of their outputs and distance components (at least one).
  std::vector<ExperimentConfig> experiments;
  // Filled from [sampler]; smc.thresholds holds one schedule per threshold component of the
  // experiments' metrics, in order, and smc.keep_outputs mirrors output.keep_simulated_curves.
  SmcOptions smc;
  // Filled from [sampler] (prior, tie) and the simulator's bits: the sensor's clamps (dimension
  // = 2 x model.clamps_per_edge, names "clamp 1", ...) or [simulator.bits].
  BinarySpaceOptions space;
  // The key that sets the number of bits (model.clamps.per_edge or section_length;
  // simulator.bits.count or names) and its line (its table's when left at its default, 0 without
  // the table), so that a later refusal of the space's size (enumerate's 2^24) names it.
  std::string bits_key = "model.clamps.per_edge";
  int bits_line = 0;
  // [parameters.<name>]: the simulator's continuous unknowns with their priors, by name in
  // alphabetical order (docs/config.md lists the names the sensor model has; an external
  // simulator takes any name).
  std::vector<ContinuousParameter> reals;
  // [[joint_prior]]: correlated Gaussian priors over reals declared with prior = "joint".
  std::vector<JointPriorGroup> joint_priors;
  OutputConfig output;
  std::optional<DesignConfig> design;  // [design], for `combabc design` only
  // [model_choice]: the candidate models of an ABC model choice (docs/config.md, "Model choice").
  std::optional<ModelChoiceConfig> model_choice;
};

// The sensor models a run builds (kind = "sensor"): one per distinct frequency among the
// experiments, in order of first use, each with those experiments' load cases in experiment order.
struct SensorModelPlan {
  plate::SensorOptions options;
  std::vector<std::size_t> experiments;  // the experiment of each load case
};
std::vector<SensorModelPlan> SensorModels(const CalibrationConfig& config);
// The same for the cheap sensor of [simulator.low_fidelity] (kind = "sensor"): its model, the
// experiments' loads, the expensive simulator's output coordinates.
std::vector<SensorModelPlan> LowFidelitySensorModels(const CalibrationConfig& config);

// `combabc design` (docs/config.md, "Design"): a free-bit space up to this size is designed over
// every configuration (the exact prior), a larger one over [design] particles prior draws.
inline constexpr int kDesignExactBits = 12;
// The scan positions of a design candidate's window [from, to] every `spacing` (m).
std::vector<double> DesignScanPositions(double from, double to, double spacing);
// The sensor `combabc design` simulates: [model] with one load case per candidate of [design], in
// the order load_x, load_y_fraction, scan, scan_y_fraction (outermost first), normalised.
plate::SensorOptions DesignSensorOptions(const CalibrationConfig& config);
// The peak memory (bytes) of `combabc design` over `particles` configurations: the sensor's
// precompute, every particle's profile under every candidate (held twice while split by
// candidate), and the scoring's per-truth log-likelihoods.
struct DesignMemory {
  double model = 0.0;
  double profiles = 0.0;
  double scoring = 0.0;
  double total() const { return model + profiles + scoring; }
};
DesignMemory EstimateDesignMemory(const CalibrationConfig& config, double particles);

// A name as its export columns write it (export.cpp's Identifier: lower case, each run of other
// characters one '_'): experiment and component names must differ there, or columns collide.
std::string ColumnKey(const std::string& name);

// Largest config file accepted (docs/config.md, "Limits"): a real config is a few KiB.
inline constexpr std::size_t kMaxConfigBytes = std::size_t{1} << 20;  // 1 MiB

// Parses and validates `text`; `path` names the file in messages and sets `directory`.
CalibrationConfig ParseConfig(std::string_view text, const std::string& path);
// Reads `path` and parses it; a missing or unreadable file is combabc::Error(kNoInput), one over
// kMaxConfigBytes (checked while reading, so FIFOs and devices too) kConfig.
CalibrationConfig LoadConfig(const std::string& path);

}  // namespace combabc
