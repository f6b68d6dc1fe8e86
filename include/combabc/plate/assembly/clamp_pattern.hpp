#pragma once
// The sensor's clamp configuration as bits (docs/model.md, "Edges"): each long edge is split into
// n equal sections along x, one clamp each; the 2 n bytes hold edge A's (y = 0) sections in order
// of x, then edge B's (y = width), and a nonzero byte fixes its clamp (1-based clamp k is section
// k of edge A for k <= n, else section k - n of edge B). The one place that knows this layout:
// the model's constraints, both condensations and the config go through it.
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "combabc/core/error.hpp"

namespace combabc::plate {

class ClampPattern {
 public:
  static constexpr int kEdgeA = 0;  // y = 0
  static constexpr int kEdgeB = 1;  // y = width
  // Clamp states of one section: bit 0 its edge-A clamp fixed, bit 1 its edge-B clamp.
  static constexpr int kSectionStates = 4;

  // The number of clamps (bits) of a sensor with `per_edge` sections per edge.
  static constexpr int Size(int per_edge) { return 2 * per_edge; }
  // The bit of section `section` (0-based along x) of `edge`, and back.
  static constexpr int Index(int edge, int section, int per_edge) {
    return edge * per_edge + section;
  }
  static constexpr int EdgeOf(int index, int per_edge) {
    return index < per_edge ? kEdgeA : kEdgeB;
  }
  static constexpr int SectionOf(int index, int per_edge) {
    return index < per_edge ? index : index - per_edge;
  }
  // The bits of the clamps that `fixed_a` and `fixed_b` (per section, along x) fix.
  static std::vector<std::uint8_t> Encode(const std::vector<bool>& fixed_a,
                                          const std::vector<bool>& fixed_b) {
    std::vector<std::uint8_t> bits;
    bits.reserve(fixed_a.size() + fixed_b.size());
    for (bool fixed : fixed_a) bits.push_back(fixed ? 1 : 0);
    for (bool fixed : fixed_b) bits.push_back(fixed ? 1 : 0);
    return bits;
  }

  // A view of `bits` (which must outlive it) for `per_edge` sections per edge. Throws
  // Error(kConfig) at "clamps" unless there are Size(per_edge) bits and per_edge >= 1.
  ClampPattern(std::span<const std::uint8_t> bits, int per_edge) : bits_(bits), n_(per_edge) {
    if (per_edge < 1 || bits.size() != static_cast<std::size_t>(Size(per_edge))) {
      throw Error(ErrorKind::kConfig,
                  "has " + std::to_string(bits.size()) + " entries; " + std::to_string(per_edge) +
                      " sections per edge take " + std::to_string(Size(per_edge)),
                  "",
                  0,
                  "clamps");
    }
  }

  int sections_per_edge() const { return n_; }
  // Whether the clamp of section `section` of `edge` is fixed.
  bool Fixed(int edge, int section) const {
    return bits_[static_cast<std::size_t>(Index(edge, section, n_))] != 0;
  }
  // Section `section`'s state (kSectionStates: bit 0 edge A fixed, bit 1 edge B fixed).
  int State(int section) const {
    return (Fixed(kEdgeA, section) ? 1 : 0) | (Fixed(kEdgeB, section) ? 2 : 0);
  }
  // Whether the node of `edge` on section boundary `boundary` (0..n, x_0 < ... < x_n) is fixed:
  // it is when either adjoining section's clamp fixes it (closed intervals, docs/model.md).
  bool BoundaryFixed(int edge, int boundary) const {
    return (boundary > 0 && Fixed(edge, boundary - 1)) || (boundary < n_ && Fixed(edge, boundary));
  }

 private:
  std::span<const std::uint8_t> bits_;
  int n_;
};

}  // namespace combabc::plate
