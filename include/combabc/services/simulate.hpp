#pragma once
// `combabc simulate` and the Python module's SensorModel: one bit configuration through the
// config's simulator at its nominal continuous values.
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "combabc/config/config.hpp"
#include "combabc/samplers/simulator.hpp"

namespace combabc::services {

// The config's simulator at its nominal continuous values (the sensor at its [model] values; an
// external simulator without continuous parameters), as `combabc simulate` runs it; the Python
// module's SensorModel. Building it is the costly part (the sensor's precompute); Simulate may be
// called from several threads at once (Simulator's contract).
class NominalSimulator {
 public:
  // work_directory: where an external simulator makes its folders. A config whose external
  // simulator has continuous parameters is refused (kUsage). low_fidelity: the config's cheap
  // simulator ([simulator.low_fidelity]) instead, at the expensive one's output coordinates (a
  // config without one is refused, kUsage).
  NominalSimulator(CalibrationConfig config,
                   const std::string& work_directory,
                   bool low_fidelity = false);
  ~NominalSimulator();
  NominalSimulator(const NominalSimulator&) = delete;
  NominalSimulator& operator=(const NominalSimulator&) = delete;

  int dimension() const;
  int output_size() const { return static_cast<int>(positions().size()); }
  const std::vector<double>& positions() const;  // the outputs' coordinates (the sensor: metres)
  const std::string& output_name() const;        // the sensor: "displacement"
  bool is_sensor() const;
  const CalibrationConfig& config() const { return config_; }
  // One configuration's raw output (the sensor: |w| in metres along the centreline). A failed
  // simulation is Error kSoftware.
  std::vector<double> Simulate(std::span<const std::uint8_t> bits) const;
  // "0110..." (one character per bit) as bits, checked against the config: kUsage naming
  // --clamps.
  static std::vector<std::uint8_t> ParseBits(const CalibrationConfig& config,
                                             const std::string& clamps);
  std::vector<std::uint8_t> ParseBits(const std::string& clamps) const {
    return ParseBits(config_, clamps);
  }

 private:
  CalibrationConfig config_;
  bool sensor_ = true;  // the simulator run is the built-in sensor
  // An external simulator's work folder: removed, if combabc made it and it is empty, after the
  // simulator has gone.
  std::shared_ptr<const void> work_folder_;
  std::unique_ptr<Simulator> simulator_;
};

// One bit configuration ("0110..." with one character per bit; for the sensor one per clamp,
// 1 = fixed) through the config's simulator at its nominal continuous values, written as CSV:
// position_m (the output coordinates), the output (the sensor's: displacement_m, raw metres) and
// the profile normalised by its largest magnitude; with [[experiment]] tables, every
// experiment's profile, each normalised by its own peak, after a column naming the experiment. An
// external simulator works in
// "<csv stem>.simulate.work" beside the CSV. An existing output_csv is refused (kCantCreate)
// unless `overwrite`. low_fidelity: the config's cheap simulator instead (NominalSimulator).
void SimulateConfiguration(const std::string& config_path,
                           const std::string& clamps,
                           const std::string& output_csv,
                           bool overwrite = false,
                           bool low_fidelity = false);

}  // namespace combabc::services
