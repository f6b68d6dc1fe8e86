#pragma once
// The measured displacement profile Y (paper Figures 1 and 7): a CSV of positions along the
// sensor and displacements, converted to SI (metres) at this I/O edge, optionally windowed,
// extended toward the load by a Gaussian fit (section 5) and normalised to [0, 1] by its maximum
// (section 5: "both datasets are normalised by the maximum value").
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>
#include "combabc/core/enum_names.hpp"

#include "combabc/data/gaussian_extension.hpp"

namespace combabc {

// Length units accepted at the I/O edge; everything inside is metres.
enum class LengthUnit { kMetre, kCentimetre, kMillimetre, kMicrometre, kNanometre };
template <>
struct EnumNames<LengthUnit> {
  static constexpr std::pair<LengthUnit, const char*> kNames[] = {
      {LengthUnit::kMetre, "m"},
      {LengthUnit::kCentimetre, "cm"},
      {LengthUnit::kMillimetre, "mm"},
      {LengthUnit::kMicrometre, "um"},
      {LengthUnit::kNanometre, "nm"},
  };
};
double MetresPer(LengthUnit unit);  // e.g. 0.01 for kCentimetre

struct DataConfig {
  // CSV file with a header row; relative paths are resolved against the config file's directory.
  std::string csv;
  std::string position_column = "position";
  std::string displacement_column = "displacement";
  LengthUnit position_unit = LengthUnit::kCentimetre;
  LengthUnit displacement_unit = LengthUnit::kMetre;
  // Optional [x_min, x_max] in metres (the config converts from position_unit); only rows inside
  // it are kept. It must lie within the measured range.
  std::optional<double> window_min;
  std::optional<double> window_max;
  // Divide the profile by its maximum absolute value (paper section 5). The metrics then also
  // normalise each simulated profile by its own maximum.
  bool normalise = true;
  // Positions are configured in metres here (the config converts from position_unit).
  GaussianExtensionOptions gaussian_extension;
};

struct MeasuredData {
  std::string source;                   // the CSV path that was read
  std::vector<double> positions;        // metres, strictly increasing
  std::vector<double> displacements;    // metres, or dimensionless in [0, 1] when normalised
  std::vector<std::uint8_t> synthetic;  // 1 for points synthesised by the Gaussian extension
  bool normalised = false;
  double scale = 1.0;  // metres per unit of `displacements` (the maximum when normalised)
  std::optional<GaussianFit> gaussian_fit;  // in metres (before normalisation)

  std::size_t size() const { return positions.size(); }
};

// Largest measured-data CSV accepted (docs/config.md, "Limits"): about three million rows.
inline constexpr std::size_t kMaxCsvBytes = std::size_t{64} << 20;  // 64 MiB

// Reads, converts, windows, extends and normalises the profile described by `config`. Throws
// combabc::Error(kNoInput) if the file cannot be read; kData for a file over kMaxCsvBytes
// (checked while reading, so FIFOs and devices too) and, naming file:line and the column, for a
// missing column, a non-numeric / NaN / infinite cell, an empty file, malformed CSV (quoting, a row
// wider or narrower than the header, a repeated header name: data/csv_reader.hpp), unsorted or
// duplicate positions, a window outside the data or a failed Gaussian extension.
MeasuredData LoadMeasuredData(const DataConfig& config, const std::string& config_dir);

// Same, from CSV text already in memory; `path` is used in messages only.
MeasuredData ParseMeasuredData(const std::string& text,
                               const std::string& path,
                               const DataConfig& config);

// `path` if absolute or `base_dir` is empty, else base_dir/path.
std::string ResolvePath(const std::string& base_dir, const std::string& path);

}  // namespace combabc
