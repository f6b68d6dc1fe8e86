#pragma once
// Priors given by code, over one real or a group of reals: a normalised log density and a sampler
// (a custom prior), or a correlated Gaussian. Each real of the group is declared with
// PriorKind::kJoint, whose low and high bound its support; ParameterSpace checks the density
// against the sampler before any simulation (CheckJointPrior).
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "combabc/params/continuous_prior.hpp"
#include "combabc/rng/random_stream.hpp"

namespace combabc {

class JointPrior {
 public:
  virtual ~JointPrior() = default;
  // Number of reals it covers.
  virtual int dimension() const = 0;
  // Normalised log density of a point (dimension() values); -infinity outside the support. The
  // normaliser matters: a mixed proposal may mix the prior into itself, and the evidence uses it.
  virtual double LogDensity(std::span<const double> x) const = 0;
  // One draw into x (dimension() values) using only `rng`, so that a candidate's draw does not
  // depend on threads. Called from several threads at once.
  virtual void Sample(RandomStream& rng, std::span<double> x) const = 0;
  // For the run fingerprint: the parameters of a built-in prior, "custom" for code.
  virtual std::string Describe() const = 0;
};

// A prior from two functions (C++, or the Python binding's callables). Both must be thread-safe.
using LogDensityFunction = std::function<double(std::span<const double>)>;
using SampleFunction = std::function<void(RandomStream&, std::span<double>)>;
std::shared_ptr<const JointPrior> MakeCustomPrior(int dimension,
                                                  LogDensityFunction log_density,
                                                  SampleFunction sample);

// The most reals one joint prior may cover: CheckJointPrior's importance sampling loses ~1.2x of
// its efficiency per dimension and refuses a Gaussian beyond ~25, and its cost grows as d^2, so a
// larger group is refused up front (split it into independent groups).
inline constexpr int kMaxJointPriorDimension = 64;

// N(mean, covariance): covariance is d x d, row-major, symmetric positive definite, d at most
// kMaxJointPriorDimension. Throws combabc::Error(kConfig) otherwise, naming the entry.
std::shared_ptr<const JointPrior> MakeMultivariateNormalPrior(std::vector<double> mean,
                                                              std::vector<double> covariance);

// One prior for the reals named `names` (its coordinates, in this order).
struct JointPriorGroup {
  std::vector<std::string> names;
  std::shared_ptr<const JointPrior> prior;
};

// The prior restricted to the box [low[k], high[k]] of its reals, normalised there, so that its
// draws stay inside and its density is exact: a multivariate normal prior whose covariance is
// diagonal becomes a product of truncated normals (sampled exactly, normalised exactly); a
// correlated one is kept as it is (its draws redrawn whole if outside) when all but 1e-9 of its
// mass lies inside (the union bound over its marginals), and is otherwise refused, naming the real
// with the most mass outside: a correlated normal's mass in a box has no closed form. Any other
// prior (custom) is returned as it is: its sampler must stay inside the bounds itself.
// Throws combabc::Error(kConfig) with the field `names[k]`.
std::shared_ptr<const JointPrior> RestrictJointPrior(std::shared_ptr<const JointPrior> prior,
                                                     std::span<const std::string> names,
                                                     std::span<const double> low,
                                                     std::span<const double> high);

// The per-coordinate mean and standard deviation of a checked joint prior's draws.
struct JointPriorMoments {
  std::vector<double> mean, sd;
};

// Checks a joint prior over reals with supports [low[k], high[k]] on draws of its sampler, with
// a fixed stream (so it never flakes): every draw is finite, inside the bounds, of finite log
// density; and the sampler and the density agree, by comparing the draws' means and covariances,
// and the density's total mass (1), with importance-sampling estimates under the density from a
// wide reference distribution (docs/algorithm.md, "Custom and joint priors").
// Throws combabc::Error(kConfig) with one line naming the parameter (`names[k]`) at fault.
JointPriorMoments CheckJointPrior(const JointPrior& prior,
                                  std::span<const std::string> names,
                                  std::span<const double> low,
                                  std::span<const double> high);

}  // namespace combabc
