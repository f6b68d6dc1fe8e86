#include "combabc/data/measured_data.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string_view>

#include "combabc/core/bounded_read.hpp"
#include "combabc/core/error.hpp"
#include "combabc/data/csv_reader.hpp"

namespace combabc {
namespace {

// Window edges are compared with this slack (metres) so that a window written in the data's own
// unit (48 cm) matches the converted positions despite rounding in the unit conversion.
constexpr double kPositionTolerance = 1e-9;

std::string_view TrimBlanks(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

// A whole (trimmed) cell as a finite number: "12", "-1.5e-6", "+3". Anything else, "12abc",
// "1 2", "0x10", text, is refused rather than read as a prefix or as 0. `column` is 1-based.
double ParseCell(std::string_view raw,
                 const std::string& path,
                 int line,
                 int column,
                 const std::string& column_name) {
  auto fail = [&](const std::string& message) {
    throw Error(ErrorKind::kData, message, path, line, column_name, column);
  };
  // libcsv drops the blanks around an unquoted cell; those inside quotes ("  12 ") go here.
  const std::string_view cell = TrimBlanks(raw);
  if (cell.empty()) fail("empty cell");
  std::string_view digits = cell;
  if (digits.front() == '+') digits.remove_prefix(1);
  double value = 0.0;
  const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
  if (ec == std::errc::result_out_of_range) fail("number out of range: " + Excerpt(cell));
  if (ec != std::errc() || end != digits.data() + digits.size() || digits.empty()) {
    fail("not a number: " + Excerpt(cell));
  }
  if (std::isnan(value)) fail("value is NaN");
  if (std::isinf(value)) fail("value is infinite");
  return value;
}

int ColumnNumber(std::size_t index) { return static_cast<int>(index) + 1; }

std::string FormatMetres(double x) {
  std::ostringstream out;
  out << x << " m";
  return out.str();
}

}  // namespace

double MetresPer(LengthUnit unit) {
  switch (unit) {
    case LengthUnit::kMetre:
      return 1.0;
    case LengthUnit::kCentimetre:
      return 1e-2;
    case LengthUnit::kMillimetre:
      return 1e-3;
    case LengthUnit::kMicrometre:
      return 1e-6;
    case LengthUnit::kNanometre:
      return 1e-9;
  }
  return 1.0;
}

std::string ResolvePath(const std::string& base_dir, const std::string& path) {
  const std::filesystem::path p(path);
  if (p.is_absolute() || base_dir.empty()) return path;
  return (std::filesystem::path(base_dir) / p).string();
}

MeasuredData ParseMeasuredData(const std::string& text,
                               const std::string& path,
                               const DataConfig& config) {
  CsvReader csv(text, path);
  const std::vector<std::string>& header = csv.ReadHeader();
  const int header_number = csv.line();

  auto find_column = [&](const std::string& name) {
    const auto it = std::find(header.begin(), header.end(), name);
    if (it == header.end()) {
      // A few names only: the file may not be the one intended, and is echoed in excerpts.
      constexpr std::size_t kNamesShown = 6;
      std::string have;
      for (std::size_t k = 0; k < std::min(header.size(), kNamesShown); ++k) {
        have += (have.empty() ? "" : ", ") + Excerpt(header[k]);
      }
      if (header.size() > kNamesShown) have += ", ...";
      throw Error(ErrorKind::kData,
                  "missing column " + Excerpt(name) + " (header has: " + have + ")",
                  path,
                  header_number,
                  name);
    }
    return static_cast<std::size_t>(it - header.begin());
  };
  const std::size_t x_col = find_column(config.position_column);
  const std::size_t y_col = find_column(config.displacement_column);

  const double x_scale = MetresPer(config.position_unit);
  const double y_scale = MetresPer(config.displacement_unit);
  std::vector<double> xs, ys;
  std::vector<int> lines;
  while (csv.Next()) {
    const int line = csv.line();
    const std::vector<std::string>& cells = csv.cells();
    const double x =
        ParseCell(cells[x_col], path, line, ColumnNumber(x_col), config.position_column) * x_scale;
    const double y =
        ParseCell(cells[y_col], path, line, ColumnNumber(y_col), config.displacement_column) *
        y_scale;
    if (!xs.empty() && x <= xs.back()) {
      throw Error(
          ErrorKind::kData,
          std::string(x == xs.back() ? "duplicate position " : "positions must increase: ") +
              Excerpt(cells[x_col]) + " after line " + std::to_string(lines.back()),
          path,
          line,
          config.position_column,
          ColumnNumber(x_col));
    }
    xs.push_back(x);
    ys.push_back(y);
    lines.push_back(line);
  }
  if (xs.empty()) {
    throw Error(ErrorKind::kData, "no data rows after the header", path, header_number);
  }

  MeasuredData data;
  data.source = path;
  // Window: kept rows are those inside [window_min, window_max]; the window must lie inside the
  // measured range, otherwise the metric would silently compare over less than was asked for.
  const double lo = config.window_min.value_or(xs.front());
  const double hi = config.window_max.value_or(xs.back());
  if (lo < xs.front() - kPositionTolerance || hi > xs.back() + kPositionTolerance) {
    throw Error(ErrorKind::kData,
                "window [" + FormatMetres(lo) + ", " + FormatMetres(hi) +
                    "] lies outside the measured range [" + FormatMetres(xs.front()) + ", " +
                    FormatMetres(xs.back()) + "]",
                path,
                0,
                "data.window");
  }
  for (std::size_t i = 0; i < xs.size(); ++i) {
    if (xs[i] >= lo - kPositionTolerance && xs[i] <= hi + kPositionTolerance) {
      data.positions.push_back(xs[i]);
      data.displacements.push_back(ys[i]);
    }
  }
  if (data.positions.empty()) {
    throw Error(ErrorKind::kData, "no data rows inside the window", path, 0, "data.window");
  }
  data.synthetic.assign(data.positions.size(), 0);

  if (config.gaussian_extension.enabled) {
    GaussianExtension extension;
    try {
      extension = ExtendWithGaussian(config.gaussian_extension, data.positions, data.displacements);
    } catch (const Error& e) {
      throw Error(ErrorKind::kData, e.message(), path, 0, "data.gaussian_extension");
    }
    const bool before =
        extension.positions.empty() || extension.positions.front() < data.positions.front();
    const auto n = extension.positions.size();
    const auto at = before ? std::ptrdiff_t{0} : static_cast<std::ptrdiff_t>(data.size());
    data.positions.insert(
        data.positions.begin() + at, extension.positions.begin(), extension.positions.end());
    data.displacements.insert(
        data.displacements.begin() + at, extension.values.begin(), extension.values.end());
    data.synthetic.insert(data.synthetic.begin() + at, n, std::uint8_t{1});
    data.gaussian_fit = extension.fit;
  }

  if (config.normalise) {
    double peak = 0.0;
    for (double y : data.displacements) peak = std::max(peak, std::abs(y));
    if (!(peak > 0.0)) {
      throw Error(ErrorKind::kData,
                  "all displacements are zero; cannot normalise",
                  path,
                  0,
                  config.displacement_column);
    }
    for (double& y : data.displacements) y /= peak;
    data.normalised = true;
    data.scale = peak;
  }
  return data;
}

MeasuredData LoadMeasuredData(const DataConfig& config, const std::string& config_dir) {
  const std::string path = ResolvePath(config_dir, config.csv);
  if (config.csv.empty()) throw Error(ErrorKind::kNoInput, "no CSV file given", {}, 0, "data.csv");
  const std::string text = ReadBoundedFile(path, kMaxCsvBytes, "data file", ErrorKind::kData);
  return ParseMeasuredData(text, path, config);
}

}  // namespace combabc
