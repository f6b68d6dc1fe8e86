#pragma once
// A distance D(Y, Y*) between the observed data (held by the implementation) and a simulated
// output. It may be vector-valued (paper Eq. 6): a candidate is accepted when every threshold
// component satisfies d_k <= eps_k, every indicator component (Eq. 7's H1, H2) equals its
// required value, and a uniform u < exp(-sum_k (d_k - m_k) / T_k) over the negative
// log-likelihood components (noise-aware acceptance, Wilkinson 2013; docs/algorithm.md).
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "combabc/core/batch_failures.hpp"
#include "combabc/core/enum_names.hpp"

namespace combabc {

enum class ComponentKind {
  kThreshold,  // accepted when d_k <= eps_k (eps_k from the component's threshold schedule)
  kIndicator,  // accepted when d_k == required (exact comparison: indicators are 0/1 values)
  // d_k = -log(pi(y | Y*) / c) >= 0 for an error model pi with c >= its maximum; accepted with
  // probability exp(-(d_k - m_k) / T_k), T_k >= 1 the component's temperature from its schedule
  // and m_k the smallest d_k among earlier waves' particles (0 in wave 0).
  kNegLogLikelihood,
};
template <>
struct EnumNames<ComponentKind> {
  static constexpr std::pair<ComponentKind, const char*> kNames[] = {
      {ComponentKind::kThreshold, "threshold"},
      {ComponentKind::kIndicator, "indicator"},
      {ComponentKind::kNegLogLikelihood, "neg_log_likelihood"},
  };
};

struct DistanceComponent {
  std::string name;
  ComponentKind kind = ComponentKind::kThreshold;
  double required = 1.0;  // indicator components only
};

class Distance {
 public:
  virtual ~Distance() = default;
  // Fixed for the distance's lifetime; its size is the number of components.
  virtual std::vector<DistanceComponent> components() const = 0;
  // Writes one value per component. Must be thread-safe (called concurrently, const).
  virtual void Evaluate(std::span<const double> simulated, std::span<double> out) const = 0;
  // The samplers' call: a batch of n = failures.size() outputs, row-major (simulated: n rows of m
  // values; out: n rows of one value per component). Rows already marked failed are skipped (their
  // out rows are left as they are); Fail(i, reason) marks a row the distance cannot measure, a
  // failed simulation with that reason (any exception ends the run). The values must be
  // Evaluate's, row by row, so that a history does not depend on how candidates are batched. The
  // default calls Evaluate row by row; a distance that pays per call (one written in Python)
  // overrides it. Thread-safe, as Evaluate.
  virtual void EvaluateBatch(std::span<const double> simulated,
                             std::span<double> out,
                             BatchFailures& failures) const {
    const std::size_t n = failures.size();
    if (n == 0) return;
    const std::size_t m = simulated.size() / n;
    const std::size_t k = out.size() / n;
    for (std::size_t i = 0; i < n; ++i) {
      if (!failures.failed(i)) Evaluate(simulated.subspan(i * m, m), out.subspan(i * k, k));
    }
  }
};

}  // namespace combabc
