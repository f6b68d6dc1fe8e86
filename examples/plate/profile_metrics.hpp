#pragma once
// Helpers shared by the plate theory examples (theory_comparison.cpp, theory_sweep.cpp): clamp
// configurations of the default 18 + 18 sections, and the peak and shape of a profile.
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "combabc/plate/sensor_model.hpp"

namespace plate_examples {

// Sections s (1-based, 5 cm each) of both edges fixed where pick(s) is true.
template <typename Pick>
std::vector<std::uint8_t> BothEdges(Pick pick) {
  std::vector<std::uint8_t> c(36, 0);
  for (int s = 1; s <= 18; ++s) c[s - 1] = c[s + 17] = pick(s) ? 1 : 0;
  return c;
}

// |w| (m, un-normalised) at the output positions, from the fast path.
inline std::vector<double> Magnitudes(const combabc::plate::SensorModel& model,
                                      const std::vector<std::uint8_t>& clamps) {
  std::vector<std::complex<double>> w(model.num_outputs());
  model.ComplexProfile(clamps, w);
  std::vector<double> out(w.size());
  for (std::size_t k = 0; k < w.size(); ++k) out[k] = std::abs(w[k]);
  return out;
}

inline double Peak(const std::vector<double>& p) { return *std::max_element(p.begin(), p.end()); }

// Largest difference of the two profiles, each normalised to its peak (what the calibration
// compares, as the paper's figures are normalised).
inline double ProfileDifference(const std::vector<double>& a, const std::vector<double>& b) {
  const double peak_a = Peak(a);
  const double peak_b = Peak(b);
  double d = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    d = std::max(d, std::abs(a[k] / peak_a - b[k] / peak_b));
  }
  return d;
}

}  // namespace plate_examples
