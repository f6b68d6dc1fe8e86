#include "combabc/params/joint_prior.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <limits>
#include <utility>

#include "combabc/core/check.hpp"
#include "combabc/core/error.hpp"
#include "params/truncated_normal.hpp"

namespace combabc {
namespace {

constexpr double kInfinite = std::numeric_limits<double>::infinity();
constexpr double kLogSqrtTwoPi = 0.91893853320467274178;  // log sqrt(2 pi)

// CheckJointPrior: draws of the sampler, draws of the reference distribution, and the bound on
// |sampler estimate - density estimate| in combined standard errors. 6 standard errors over the
// ~3 d comparisons of a group: a false alarm has probability ~1e-8 under normal errors, and the
// fixed stream makes the outcome the same on every run. A sampler and a density that differ by
// 0.1 sd in a mean or 10% in a variance are still caught (standard errors ~0.02 sd).
constexpr int kDraws = 4000;
constexpr int kReferenceDraws = 16000;
constexpr double kBound = 6.0;
// The reference is 0.5 N(m, (1.5)^2 S) + 0.5 N(m, 3^2 S), m and S the draws' mean and covariance:
// wider than the prior in every direction, so the importance weights p / r stay bounded for a
// prior with Gaussian or lighter tails, and its efficiency falls only ~1.2x per dimension.
constexpr double kNarrowScale = 1.5;
constexpr double kWideScale = 3.0;
// Below this effective number of reference draws the importance-sampling estimates (and their
// standard errors) cannot be trusted: the check refuses rather than guess.
constexpr double kMinReferenceEss = 100.0;
// The check's own stream: the same draws whatever the run's seed.
constexpr std::uint64_t kCheckSeed = 0x70A1C4ECBULL;

std::string Shortest(double x) {
  std::array<char, 32> buf{};
  const auto result = std::to_chars(buf.data(), buf.data() + buf.size(), x);
  return {buf.data(), result.ptr};
}

// The number rounded to 3 significant digits, for messages that compare estimates.
std::string Short(double x) {
  std::array<char, 32> buf{};
  const auto result =
      std::to_chars(buf.data(), buf.data() + buf.size(), x, std::chars_format::general, 3);
  return {buf.data(), result.ptr};
}

// Lower-triangular Cholesky factor of the d x d row-major `a` (packed row by row into a full
// d x d), or false when `a` is not positive definite.
bool Cholesky(const std::vector<double>& a, std::size_t d, std::vector<double>* l) {
  l->assign(d * d, 0.0);
  for (std::size_t i = 0; i < d; ++i) {
    for (std::size_t k = 0; k <= i; ++k) {
      double s = a[i * d + k];
      for (std::size_t j = 0; j < k; ++j) s -= (*l)[i * d + j] * (*l)[k * d + j];
      if (i == k) {
        if (!(s > 0.0) || !std::isfinite(s)) return false;
        (*l)[i * d + i] = std::sqrt(s);
      } else {
        (*l)[i * d + k] = s / (*l)[k * d + k];
      }
    }
  }
  return true;
}

class CustomPrior final : public JointPrior {
 public:
  CustomPrior(int dimension, LogDensityFunction log_density, SampleFunction sample)
      : dimension_(dimension), log_density_(std::move(log_density)), sample_(std::move(sample)) {}
  int dimension() const override { return dimension_; }
  double LogDensity(std::span<const double> x) const override { return log_density_(x); }
  void Sample(RandomStream& rng, std::span<double> x) const override { sample_(rng, x); }
  std::string Describe() const override { return "custom"; }

 private:
  int dimension_;
  LogDensityFunction log_density_;
  SampleFunction sample_;
};

class MultivariateNormalPrior final : public JointPrior {
 public:
  MultivariateNormalPrior(std::vector<double> mean,
                          std::vector<double> covariance,
                          std::vector<double> l)
      : mean_(std::move(mean)), covariance_(std::move(covariance)), l_(std::move(l)) {
    const std::size_t d = mean_.size();
    log_norm_ = -static_cast<double>(d) * kLogSqrtTwoPi;
    for (std::size_t i = 0; i < d; ++i) log_norm_ -= std::log(l_[i * d + i]);
  }
  int dimension() const override { return static_cast<int>(mean_.size()); }
  double LogDensity(std::span<const double> x) const override {
    const std::size_t d = mean_.size();
    COMBABC_CHECK(x.size() == d);
    // |L^{-1} (x - mean)|^2 by forward substitution, one row at a time.
    std::vector<double> y(d);
    double q = 0.0;
    for (std::size_t i = 0; i < d; ++i) {
      double s = x[i] - mean_[i];
      for (std::size_t k = 0; k < i; ++k) s -= l_[i * d + k] * y[k];
      y[i] = s / l_[i * d + i];
      q += y[i] * y[i];
    }
    return std::isfinite(q) ? log_norm_ - 0.5 * q : -kInfinite;
  }
  void Sample(RandomStream& rng, std::span<double> x) const override {
    const std::size_t d = mean_.size();
    COMBABC_CHECK(x.size() == d);
    for (std::size_t i = 0; i < d; ++i) x[i] = rng.Normal();
    // x = mean + L z in place, from the last row up (row i needs z_0..z_i).
    for (std::size_t i = d; i-- > 0;) {
      double r = mean_[i];
      for (std::size_t k = 0; k <= i; ++k) r += l_[i * d + k] * x[k];
      x[i] = r;
    }
  }
  const std::vector<double>& mean() const { return mean_; }
  const std::vector<double>& covariance() const { return covariance_; }
  std::string Describe() const override {
    std::string text = "normal(mean=";
    for (const double m : mean_) text += Shortest(m) + ",";
    text += " covariance=";
    for (const double c : covariance_) text += Shortest(c) + ",";
    return text + ")";
  }

 private:
  std::vector<double> mean_, covariance_, l_;
  double log_norm_ = 0.0;
};

// A multivariate normal restricted to a box and normalised there (RestrictJointPrior). Diagonal:
// each coordinate a truncated normal, drawn exactly, log_mass the sum of theirs. Otherwise (only
// with all but kNegligibleMass of the mass inside): drawn whole until inside, log_mass taken as 0
// (off by at most kNegligibleMass).
class BoxedNormalPrior final : public JointPrior {
 public:
  BoxedNormalPrior(std::shared_ptr<const MultivariateNormalPrior> normal,
                   std::vector<double> low,
                   std::vector<double> high,
                   bool diagonal)
      : normal_(std::move(normal)), low_(std::move(low)), high_(std::move(high)) {
    const std::size_t d = low_.size();
    for (std::size_t k = 0; diagonal && k < d; ++k) {
      const double sd = std::sqrt(normal_->covariance()[k * d + k]);
      const double a = (low_[k] - normal_->mean()[k]) / sd,
                   b = (high_[k] - normal_->mean()[k]) / sd;
      sd_.push_back(sd);
      a_.push_back(a);
      b_.push_back(b);
      log_mass_k_.push_back(LogStandardNormalMass(a, b));
      log_mass_ += log_mass_k_.back();
    }
  }
  int dimension() const override { return normal_->dimension(); }
  double LogDensity(std::span<const double> x) const override {
    return Inside(x) ? normal_->LogDensity(x) - log_mass_ : -kInfinite;
  }
  void Sample(RandomStream& rng, std::span<double> x) const override {
    if (!sd_.empty()) {
      for (std::size_t k = 0; k < x.size(); ++k) {
        const double z = SampleStandardTruncated(a_[k], b_[k], log_mass_k_[k], rng);
        // z is in [a, b]; mean + sd z may round a hair outside [low, high].
        x[k] = std::clamp(normal_->mean()[k] + sd_[k] * z, low_[k], high_[k]);
      }
      return;
    }
    for (;;) {  // P(outside) <= 1e-12: a second try is already rare
      normal_->Sample(rng, x);
      if (Inside(x)) return;
    }
  }
  std::string Describe() const override { return normal_->Describe(); }  // bounds: the reals'

 private:
  bool Inside(std::span<const double> x) const {
    for (std::size_t k = 0; k < x.size(); ++k) {
      if (!(x[k] >= low_[k] && x[k] <= high_[k])) return false;
    }
    return true;
  }

  std::shared_ptr<const MultivariateNormalPrior> normal_;
  std::vector<double> low_, high_;
  std::vector<double> sd_, a_, b_, log_mass_k_;  // diagonal only
  double log_mass_ = 0.0;
};

// A correlated normal is truncated only where the mass outside its box is below this (the union
// bound over the coordinates, about 6 sd from a single bound): its normaliser, taken as 1, is
// then off by less, far below any Monte Carlo error.
constexpr double kNegligibleMass = 1e-9;
// A diagonal normal's truncation needs this much mass left in each coordinate, as a
// truncated_normal prior does (ContinuousPrior::IsValid).
constexpr double kMinBoxMass = 1e-12;

// The names of a group, "a, b", for messages about the group as a whole.
std::string Joined(std::span<const std::string> names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

}  // namespace

std::shared_ptr<const JointPrior> MakeCustomPrior(int dimension,
                                                  LogDensityFunction log_density,
                                                  SampleFunction sample) {
  if (dimension < 1) {
    throw Error(ErrorKind::kConfig,
                "custom prior: dimension = " + std::to_string(dimension) + "; must be >= 1");
  }
  if (!log_density || !sample) {
    throw Error(ErrorKind::kConfig, "custom prior: needs both a log density and a sampler");
  }
  return std::make_shared<CustomPrior>(dimension, std::move(log_density), std::move(sample));
}

std::shared_ptr<const JointPrior> MakeMultivariateNormalPrior(std::vector<double> mean,
                                                              std::vector<double> covariance) {
  const std::size_t d = mean.size();
  auto fail = [](const std::string& why) {
    throw Error(ErrorKind::kConfig, "joint normal prior: " + why);
  };
  if (d == 0) fail("mean is empty; needs one value per parameter");
  if (d > static_cast<std::size_t>(kMaxJointPriorDimension)) {
    fail("mean has " + std::to_string(d) + " entries; a joint prior covers at most " +
         std::to_string(kMaxJointPriorDimension) +
         " reals (its check before the run cannot judge more): split it into independent groups");
  }
  if (covariance.size() != d * d) {
    fail("covariance has " + std::to_string(covariance.size()) + " entries; must be " +
         std::to_string(d) + " x " + std::to_string(d));
  }
  for (std::size_t i = 0; i < d; ++i) {
    if (!std::isfinite(mean[i])) {
      fail("mean[" + std::to_string(i) + "] = " + Shortest(mean[i]) + "; must be finite");
    }
    for (std::size_t k = 0; k < d; ++k) {
      const double a = covariance[i * d + k], b = covariance[k * d + i];
      if (!std::isfinite(a)) {
        fail("covariance[" + std::to_string(i) + "][" + std::to_string(k) + "] = " + Shortest(a) +
             "; must be finite");
      }
      if (a != b) {
        fail("covariance[" + std::to_string(i) + "][" + std::to_string(k) + "] = " + Shortest(a) +
             " but covariance[" + std::to_string(k) + "][" + std::to_string(i) +
             "] = " + Shortest(b) + "; must be symmetric");
      }
    }
  }
  std::vector<double> l;
  if (!Cholesky(covariance, d, &l)) fail("covariance is not positive definite");
  return std::make_shared<MultivariateNormalPrior>(
      std::move(mean), std::move(covariance), std::move(l));
}

std::shared_ptr<const JointPrior> RestrictJointPrior(std::shared_ptr<const JointPrior> prior,
                                                     std::span<const std::string> names,
                                                     std::span<const double> low,
                                                     std::span<const double> high) {
  auto normal = std::dynamic_pointer_cast<const MultivariateNormalPrior>(prior);
  if (!normal) return prior;
  const std::size_t d = normal->mean().size();
  COMBABC_CHECK(names.size() == d && low.size() == d && high.size() == d);
  const std::vector<double>& cov = normal->covariance();
  bool diagonal = true;
  double outside = 0.0, worst = -1.0;
  std::size_t worst_k = 0;
  for (std::size_t k = 0; k < d; ++k) {
    for (std::size_t i = 0; i < d; ++i) diagonal = diagonal && (i == k || cov[k * d + i] == 0.0);
    const double sd = std::sqrt(cov[k * d + k]);
    const double a = (low[k] - normal->mean()[k]) / sd, b = (high[k] - normal->mean()[k]) / sd;
    // The marginal's mass outside [low, high]: Phi(a) + Q(b), each from its own tail.
    const double out = 0.5 * std::erfc(-a / std::sqrt(2.0)) + 0.5 * std::erfc(b / std::sqrt(2.0));
    outside += out;
    if (out > worst) {
      worst = out;
      worst_k = k;
    }
  }
  if (outside == 0.0) return prior;  // nothing to cut, to double precision
  if (outside <= kNegligibleMass) {
    // Drawn whole until inside: the same draws as the normal's own, but never outside.
    return std::make_shared<BoxedNormalPrior>(std::move(normal),
                                              std::vector<double>(low.begin(), low.end()),
                                              std::vector<double>(high.begin(), high.end()),
                                              false);
  }
  if (!diagonal) {
    const double sd = std::sqrt(cov[worst_k * d + worst_k]);
    throw Error(ErrorKind::kConfig,
                "prior: the correlated normal puts " + Short(worst) + " of its mass outside [" +
                    Shortest(low[worst_k]) + ", " + Shortest(high[worst_k]) + "] (mean " +
                    Shortest(normal->mean()[worst_k]) + ", sd " + Short(sd) +
                    "); a correlated normal is truncated only where under 1e-9 of its mass is "
                    "cut (its mass in a box has no closed form): widen the bounds to mean +- 6.2 "
                    "sd, or give the group a diagonal covariance",
                "",
                0,
                names[worst_k]);
  }
  // A truncation with too little mass left could not be sampled or normalised reliably.
  for (std::size_t k = 0; k < d; ++k) {
    const double sd = std::sqrt(cov[k * d + k]);
    const double log_mass = LogStandardNormalMass((low[k] - normal->mean()[k]) / sd,
                                                  (high[k] - normal->mean()[k]) / sd);
    if (!(log_mass >= std::log(kMinBoxMass))) {
      throw Error(ErrorKind::kConfig,
                  "prior: the normal (mean " + Shortest(normal->mean()[k]) + ", sd " + Short(sd) +
                      ") has mass " + Short(std::exp(log_mass)) + " on [" + Shortest(low[k]) +
                      ", " + Shortest(high[k]) + "], must be >= 1e-12",
                  "",
                  0,
                  names[k]);
    }
  }
  return std::make_shared<BoxedNormalPrior>(std::move(normal),
                                            std::vector<double>(low.begin(), low.end()),
                                            std::vector<double>(high.begin(), high.end()),
                                            true);
}

namespace {

// Refuses the joint prior of CheckJointPrior at `field`.
[[noreturn]] void FailCheck(const std::string& field, const std::string& why) {
  throw Error(ErrorKind::kConfig, "prior: " + why, "", 0, field);
}

// The sampler's draws (kDraws x d, row-major), their moments, covariance (d x d) and its Cholesky
// factor: step 1 of CheckJointPrior.
struct SamplerDraws {
  std::vector<double> draws;
  JointPriorMoments moments;
  std::vector<double> cov;
  std::vector<double> l;
};

// The reference draws (kReferenceDraws x d) and their importance weights p / r, shifted by the
// largest (w) with their sum: step 2 of CheckJointPrior.
struct ReferenceSample {
  std::vector<double> ref;
  std::vector<double> w;
  double sum_w = 0.0;
};

// 1. The sampler's draws: finite, inside the bounds, of finite density, spread, of full rank.
SamplerDraws DrawFromSampler(const JointPrior& prior,
                             std::span<const std::string> names,
                             std::span<const double> low,
                             std::span<const double> high,
                             RandomStream& rng) {
  const auto d = static_cast<std::size_t>(prior.dimension());
  SamplerDraws s;
  std::vector<double>& draws = s.draws;
  draws.resize(kDraws * d);
  for (std::size_t i = 0; i < kDraws; ++i) {
    const std::span<double> x(draws.data() + i * d, d);
    prior.Sample(rng, x);
    for (std::size_t k = 0; k < d; ++k) {
      if (!(x[k] >= low[k] && x[k] <= high[k]) || !std::isfinite(x[k])) {
        FailCheck(names[k],
                  "the sampler drew " + Shortest(x[k]) + ", outside the support [" +
                      Shortest(low[k]) + ", " + Shortest(high[k]) + "]");
      }
    }
    const double lp = prior.LogDensity(x);
    if (!std::isfinite(lp)) {
      FailCheck(
          Joined(names),
          "the log density is " + Shortest(lp) + " at a point the sampler drew (" + Joined(names) +
              " = " +
              [&] {
                std::string p;
                for (const double v : x) p += (p.empty() ? "" : ", ") + Shortest(v);
                return p;
              }() +
              "); it must be finite wherever the sampler draws");
    }
  }
  // Their means, covariance and fourth central moments.
  JointPriorMoments& moments = s.moments;
  moments = {std::vector<double>(d, 0.0), std::vector<double>(d, 0.0)};
  std::vector<double>& cov = s.cov;
  cov.assign(d * d, 0.0);
  const auto n = static_cast<double>(kDraws);
  for (std::size_t i = 0; i < kDraws; ++i) {
    for (std::size_t k = 0; k < d; ++k) moments.mean[k] += draws[i * d + k] / n;
  }
  for (std::size_t i = 0; i < kDraws; ++i) {
    for (std::size_t k = 0; k < d; ++k) {
      const double a = draws[i * d + k] - moments.mean[k];
      for (std::size_t j = 0; j < d; ++j) {
        cov[k * d + j] += a * (draws[i * d + j] - moments.mean[j]) / n;
      }
    }
  }
  for (std::size_t k = 0; k < d; ++k) {
    bool spread = false;
    for (std::size_t i = 1; i < kDraws && !spread; ++i) spread = draws[i * d + k] != draws[k];
    if (!spread) {
      FailCheck(names[k],
                "the sampler drew " + Shortest(draws[k]) + " every time; a prior needs a spread");
    }
    moments.sd[k] = std::sqrt(cov[k * d + k]);
  }
  if (!Cholesky(cov, d, &s.l)) {
    FailCheck(
        Joined(names),
        "the sampler's draws lie on a lower-dimensional set (a parameter is a function of the "
        "others); such a prior has no density");
  }
  return s;
}

// 2. Importance sampling under the density from the reference r (a mixture of two normals around
// the draws' mean): the density must be finite there and integrate to 1.
ReferenceSample WeighReference(const JointPrior& prior,
                               std::span<const std::string> names,
                               std::span<const double> low,
                               std::span<const double> high,
                               const SamplerDraws& s,
                               RandomStream& rng) {
  const auto d = static_cast<std::size_t>(prior.dimension());
  const JointPriorMoments& moments = s.moments;
  const std::vector<double>& l = s.l;
  double log_det_l = 0.0;
  for (std::size_t k = 0; k < d; ++k) log_det_l += std::log(l[k * d + k]);
  // log w = log p - log r.
  ReferenceSample r;
  std::vector<double>& ref = r.ref;
  ref.resize(kReferenceDraws * d);
  std::vector<double> log_w(kReferenceDraws);
  std::vector<double> z(d);
  const auto dd = static_cast<double>(d);
  for (std::size_t j = 0; j < kReferenceDraws; ++j) {
    const double scale = rng.Uniform() < 0.5 ? kNarrowScale : kWideScale;
    double z2 = 0.0;
    for (std::size_t k = 0; k < d; ++k) {
      z[k] = rng.Normal();
      z2 += z[k] * z[k];
    }
    const std::span<double> y(ref.data() + j * d, d);
    for (std::size_t k = 0; k < d; ++k) {
      double v = moments.mean[k];
      for (std::size_t i = 0; i <= k; ++i) v += scale * l[k * d + i] * z[i];
      y[k] = v;
    }
    // |L^{-1} (y - m)|^2 = scale^2 |z|^2, so each component's quadratic form is known exactly.
    auto log_normal = [&](double c) {
      const double q = z2 * scale * scale / (c * c);
      return std::log(0.5) - dd * (kLogSqrtTwoPi + std::log(c)) - log_det_l - 0.5 * q;
    };
    const double a = log_normal(kNarrowScale), b = log_normal(kWideScale);
    const double log_r = std::max(a, b) + std::log1p(std::exp(-std::fabs(a - b)));
    bool inside = true;
    for (std::size_t k = 0; k < d; ++k) inside = inside && y[k] >= low[k] && y[k] <= high[k];
    const double lp = inside ? prior.LogDensity(y) : -kInfinite;
    if (std::isnan(lp) || lp == kInfinite) {
      FailCheck(Joined(names), "the log density is " + Shortest(lp) + " at a point of the support");
    }
    log_w[j] = lp - log_r;
  }
  const double max_log_w = *std::max_element(log_w.begin(), log_w.end());
  if (!std::isfinite(max_log_w)) {
    FailCheck(Joined(names), "the log density is -inf wherever the sampler's draws spread");
  }
  std::vector<double>& w = r.w;
  w.resize(kReferenceDraws);
  double& sum_w = r.sum_w;
  double sum_w2 = 0.0;
  for (std::size_t j = 0; j < kReferenceDraws; ++j) {
    w[j] = std::exp(log_w[j] - max_log_w);
    sum_w += w[j];
    sum_w2 += w[j] * w[j];
  }
  const double ess = sum_w * sum_w / sum_w2;
  if (ess < kMinReferenceEss) {
    FailCheck(
        Joined(names),
        "cannot check the sampler against the log density: importance sampling from the draws' "
        "spread keeps an effective sample of " +
            Short(ess) + " of " + std::to_string(kReferenceDraws) +
            " (the density's mass lies where the sampler does not draw, or the group has too "
            "many dimensions: split it into independent groups)");
  }
  // The density's mass: mean of the unshifted weights, which is 1 for a normalised density.
  const auto m = static_cast<double>(kReferenceDraws);
  const double mass = std::exp(max_log_w) * sum_w / m;
  double mass_var = 0.0;
  for (const double wj : w) mass_var += (wj - sum_w / m) * (wj - sum_w / m);
  const double mass_se = std::exp(max_log_w) * std::sqrt(mass_var / (m * (m - 1.0)));
  if (std::fabs(mass - 1.0) > kBound * mass_se + 0.01) {
    FailCheck(Joined(names),
              "the density integrates to about " + Short(mass) + " (+- " + Short(mass_se) +
                  "), not 1: normalise the log density, or make the sampler draw from it");
  }
  return r;
}

// 3. The draws' means and covariances against the density's (self-normalised importance
// sampling; delta-method standard errors): the means and variances of each real, and the
// covariances of each pair, which a sampler that ignores a correlation gets wrong.
void CompareMoments(std::span<const std::string> names,
                    const SamplerDraws& s,
                    const ReferenceSample& r) {
  const std::size_t d = names.size();
  const std::vector<double>& draws = s.draws;
  const JointPriorMoments& moments = s.moments;
  const std::vector<double>& cov = s.cov;
  const std::vector<double>& ref = r.ref;
  const std::vector<double>& w = r.w;
  const double sum_w = r.sum_w;
  const auto n = static_cast<double>(kDraws);
  std::vector<double> mean(d, 0.0);
  for (std::size_t j = 0; j < kReferenceDraws; ++j) {
    for (std::size_t k = 0; k < d; ++k) mean[k] += w[j] * ref[j * d + k] / sum_w;
  }
  auto centred = [&](const std::vector<double>& points,
                     std::size_t j,
                     std::size_t k,
                     const std::vector<double>& centre) { return points[j * d + k] - centre[k]; };
  for (std::size_t k = 0; k < d; ++k) {
    double se2 = 0.0;
    for (std::size_t j = 0; j < kReferenceDraws; ++j) {
      const double u = w[j] / sum_w, a = centred(ref, j, k, mean);
      se2 += u * u * a * a;
    }
    const double bound = kBound * std::sqrt(se2 + cov[k * d + k] / n);
    if (std::fabs(moments.mean[k] - mean[k]) > bound) {
      FailCheck(names[k],
                "the sampler and the log density disagree: the draws' mean is " +
                    Short(moments.mean[k]) + ", the density's " + Short(mean[k]) + " (tolerance " +
                    Short(bound) + ")");
    }
  }
  for (std::size_t k = 0; k < d; ++k) {
    for (std::size_t i = 0; i <= k; ++i) {
      double c = 0.0;
      for (std::size_t j = 0; j < kReferenceDraws; ++j) {
        c += w[j] * centred(ref, j, k, mean) * centred(ref, j, i, mean) / sum_w;
      }
      double se2 = 0.0;
      for (std::size_t j = 0; j < kReferenceDraws; ++j) {
        const double u = w[j] / sum_w;
        const double e = centred(ref, j, k, mean) * centred(ref, j, i, mean) - c;
        se2 += u * u * e * e;
      }
      const double v = cov[k * d + i];
      double draws_var = 0.0;
      for (std::size_t j = 0; j < kDraws; ++j) {
        const double e =
            centred(draws, j, k, moments.mean) * centred(draws, j, i, moments.mean) - v;
        draws_var += e * e / n;
      }
      const double bound = kBound * std::sqrt(se2 + draws_var / n);
      if (std::fabs(v - c) <= bound) continue;
      if (i == k) {
        FailCheck(names[k],
                  "the sampler and the log density disagree: the draws' sd is " +
                      Short(std::sqrt(v)) + ", the density's " + Short(std::sqrt(c)) +
                      " (variance tolerance " + Short(bound) + ")");
      }
      FailCheck(names[k],
                "the sampler and the log density disagree: the draws' covariance with " + names[i] +
                    " is " + Short(v) + ", the density's " + Short(c) + " (tolerance " +
                    Short(bound) + ")");
    }
  }
}

}  // namespace

JointPriorMoments CheckJointPrior(const JointPrior& prior,
                                  std::span<const std::string> names,
                                  std::span<const double> low,
                                  std::span<const double> high) {
  const auto d = static_cast<std::size_t>(prior.dimension());
  COMBABC_CHECK(names.size() == d && low.size() == d && high.size() == d);
  // Before any draw: the check's cost grows as d^2 (12 s at d = 500), for a verdict that beyond
  // ~25 Gaussian dimensions is a refusal anyway.
  if (d > static_cast<std::size_t>(kMaxJointPriorDimension)) {
    FailCheck(names.front() + ", ..., " + names.back(),
              "the joint prior covers " + std::to_string(d) + " reals; at most " +
                  std::to_string(kMaxJointPriorDimension) +
                  " can be checked against its sampler: split it into independent groups");
  }
  RandomStream rng(kCheckSeed, 0, 0);
  const SamplerDraws draws = DrawFromSampler(prior, names, low, high, rng);
  const ReferenceSample reference = WeighReference(prior, names, low, high, draws, rng);
  CompareMoments(names, draws, reference);
  return draws.moments;
}

}  // namespace combabc
