// libFuzzer target: the measured-data CSV reader, combabc::LoadMeasuredData, through a real file
// (the path the CLI takes). A combabc::Error is the expected outcome for bad input; anything else
// is a finding (see fuzz_util.hpp). Seeds: fuzz/corpus/measured_data/; dictionary:
// fuzz/measured_data.dict. A profile that is returned must also keep the header's promises
// (finite, strictly increasing positions, |y| <= 1 when normalised); CheckProfile aborts if not.
//
// Input layout: the first byte XOR '0' picks the DataConfig variant (bits below), the rest is the
// CSV. So a seed starts with one byte (printable below bit 7): "0" nothing set, "1" normalise, "3"
// normalise + extension, "7" + offset, "9" normalise + window, "q" normalise + columns x/y, "\xb1"
// normalise + quoted columns.
//   bit 0: normalise                    bit 1: Gaussian extension toward x0 = 0 m
//   bit 2: the extension fits an offset  bit 3: window [0.05 m, 0.40 m]
//   bits 4-5: position unit cm, mm, m, um (the displacement unit is um, m, nm, cm alike)
//   bit 6: columns "x"/"y" instead of "position"/"displacement"
//   bit 7: columns whose header cells must be quoted, `x, cm` and `y "u"` (written "x, cm" and
//          "y ""u"""), so that the reader's RFC 4180 quoting is exercised past the header
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "combabc/core/error.hpp"
#include "combabc/data/measured_data.hpp"
#include "fuzz_util.hpp"

namespace {

combabc::DataConfig Variant(std::uint8_t v) {
  using combabc::LengthUnit;
  combabc::DataConfig config;
  config.csv = "data.csv";  // relative: resolved against the scratch directory, as a config does
  config.normalise = (v & 0x01) != 0;
  if ((v & 0x02) != 0) {
    config.gaussian_extension.enabled = true;
    config.gaussian_extension.impact_position = 0.0;
    config.gaussian_extension.spacing = 0.01;
    config.gaussian_extension.fit_offset = (v & 0x04) != 0;
    config.gaussian_extension.fit_points = config.gaussian_extension.fit_offset ? 4 : 3;
  }
  if ((v & 0x08) != 0) {
    config.window_min = 0.05;
    config.window_max = 0.40;
  }
  static constexpr LengthUnit kPosition[] = {LengthUnit::kCentimetre,
                                             LengthUnit::kMillimetre,
                                             LengthUnit::kMetre,
                                             LengthUnit::kMicrometre};
  static constexpr LengthUnit kDisplacement[] = {
      LengthUnit::kMicrometre, LengthUnit::kMetre, LengthUnit::kNanometre, LengthUnit::kCentimetre};
  config.position_unit = kPosition[(v >> 4) & 3];
  config.displacement_unit = kDisplacement[(v >> 4) & 3];
  if ((v & 0x40) != 0) {
    config.position_column = "x";
    config.displacement_column = "y";
  }
  if ((v & 0x80) != 0) {
    config.position_column = "x, cm";
    config.displacement_column = "y \"u\"";
  }
  return config;
}

// What measured_data.hpp promises of a profile it returns; a broken promise aborts (a finding).
void Check(bool ok, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "measured_data_fuzzer: broken promise: %s\n", what);
    std::abort();
  }
}

void CheckProfile(const combabc::MeasuredData& m) {
  Check(m.size() > 0, "at least one point");
  Check(m.displacements.size() == m.size() && m.synthetic.size() == m.size(), "equal lengths");
  for (std::size_t i = 0; i < m.size(); ++i) {
    Check(std::isfinite(m.positions[i]) && std::isfinite(m.displacements[i]), "finite values");
    Check(i == 0 || m.positions[i - 1] < m.positions[i], "strictly increasing positions");
    Check(!m.normalised || std::abs(m.displacements[i]) <= 1.0, "normalised to [-1, 1]");
  }
  Check(std::isfinite(m.scale) && m.scale > 0.0, "finite positive scale");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const combabc::DataConfig config = Variant(static_cast<std::uint8_t>(data[0] ^ 0x30));
  const std::string& dir = combabc::fuzz::ScratchDir();
  combabc::fuzz::WriteFile(dir + "/" + config.csv, data + 1, size - 1);
  try {
    CheckProfile(combabc::LoadMeasuredData(config, dir));
  } catch (const combabc::Error&) {
    // Expected: the input is not valid measured data for this configuration.
  }
  return 0;
}
