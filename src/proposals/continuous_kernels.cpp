#include "combabc/proposals/continuous_kernels.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "combabc/core/check.hpp"
#include "combabc/core/error.hpp"
#include "combabc/proposals/proposal_options.hpp"
#include "proposals/gaussian_factor.hpp"

namespace combabc {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

std::string Formatted(double x) {
  std::array<char, 32> buf{};
  const auto result = std::to_chars(buf.data(), buf.data() + buf.size(), x);
  return {buf.data(), result.ptr};
}

// q(r) = sum_j w_j N(r; c_j, Sigma_j) restricted to the prior's support: redrawn whole until
// inside, or, when that would rarely succeed (many bounded reals), each Gaussian truncated to the
// box of the reals' bounds coordinate by coordinate and normalised there (TruncateEachCoordinate).
// Everything is precomputed: Sample and LogDensity only read, so they are thread-safe, and they
// allocate nothing below kStackDims reals.
class GaussianMixtureProposal final : public ContinuousProposal {
 public:
  // `centres` is N x d row-major; `weights` sum to 1 (zero-weight components are dropped);
  // factor_of[j] indexes `factors`. With a single shared factor, LogDensity uses the cheaper
  // O(N d + d^2) form below.
  GaussianMixtureProposal(const ParameterSpace& space,
                          const std::vector<double>& centres,
                          const std::vector<double>& weights,
                          std::vector<Factor> factors,
                          const std::vector<std::size_t>& factor_of)
      : d_(static_cast<std::size_t>(space.num_reals())),
        prior_(space.reals_prior()),
        box_(SupportBox(prior_)),
        factors_(std::move(factors)) {
    double total = 0.0;
    for (std::size_t j = 0; j < weights.size(); ++j) {
      if (!(weights[j] > 0.0)) continue;
      total += weights[j];
      centres_.insert(centres_.end(), centres.begin() + j * d_, centres.begin() + (j + 1) * d_);
      cumulative_.push_back(total);
      factor_of_.push_back(factor_of[j]);
      log_weight_.push_back(std::log(weights[j]));
    }
    COMBABC_CHECK(!cumulative_.empty() && std::isfinite(total));
    // log of w_j / ((2 pi)^{d/2} det L_j), the Gaussian's normalising constant and the weight.
    for (std::size_t j = 0; j < log_weight_.size(); ++j) {
      log_weight_[j] += -std::log(total) - static_cast<double>(d_) * kLogRootTwoPi -
                        factors_[factor_of_[j]].log_det;
    }
    shared_ = factors_.size() == 1 && d_ <= kStackDims;
    if (shared_) {
      // Whitened centres relative to the first: L^{-1} (r - c_j) = L^{-1} (r - c_0) -
      // L^{-1} (c_j - c_0), with both terms of the scale of the spread (not of |r|), so nothing
      // cancels when the reals are large numbers with a small spread.
      const Factor& f = factors_[0];
      for (std::size_t j = 0; j < NumComponents(); ++j) {
        for (std::size_t i = 0; i < d_; ++i) {
          double y = 0.0;
          for (std::size_t k = 0; k <= i; ++k) {
            y += f.l_inv[Tri(i, k)] * (centres_[j * d_ + k] - centres_[k]);
          }
          whitened_.push_back(y);
        }
      }
    }
    truncate_ = TruncateEachCoordinate(
        cumulative_,
        centres_,
        [&](std::size_t j) -> const Factor& { return factors_[factor_of_[j]]; },
        box_);
  }

  void Sample(RandomStream& rng, std::span<double> reals) const override {
    COMBABC_CHECK(reals.size() == d_);
    std::array<double, kStackDims> stack{};
    std::vector<double> heap(truncate_ && d_ > kStackDims ? d_ : 0);
    const std::span<double> z(d_ > kStackDims ? heap.data() : stack.data(), truncate_ ? d_ : 0);
    // A draw outside the support is discarded whole and both the component and z drawn again:
    // that samples q restricted to the support, q 1_S / Z with one constant Z for the wave. Keeping
    // j and redrawing only z would truncate each component on its own, with a Z_j per component
    // that LogDensity could not omit. Truncating each coordinate instead normalises each component
    // on the box, and only a joint prior's constraint between its reals can reject its draws.
    for (int attempt = 0; attempt < kMaxSupportTries; ++attempt) {
      // Component j with probability w_j: the first cumulative weight above u x total.
      const double u = rng.Uniform() * cumulative_.back();
      const std::size_t j = std::min<std::size_t>(
          std::upper_bound(cumulative_.begin(), cumulative_.end(), u) - cumulative_.begin(),
          cumulative_.size() - 1);
      const Factor& f = factors_[factor_of_[j]];
      if (truncate_) {
        SampleInBox(f, &centres_[j * d_], box_, rng, reals, z);
      } else {
        SampleGaussian(f, &centres_[j * d_], rng, reals);
      }
      if (prior_.InSupport(reals)) return;
    }
    throw Error(ErrorKind::kSoftware,
                "continuous proposal: " + std::to_string(kMaxSupportTries) +
                    " draws in a row fell outside the prior support of the reals; the kernel has "
                    "almost no mass where the joint prior's density is positive");
  }

  // log sum_j w_j N(r; c_j, Sigma_j) by a one-pass log-sum-exp, each Gaussian divided by its mass
  // in the box when truncated; -infinity outside the support. The mass of the support under this
  // (the constant of the whole redraws) is common to the wave and omitted.
  double LogDensity(std::span<const double> reals) const override {
    COMBABC_CHECK(reals.size() == d_);
    if (!prior_.InSupport(reals)) return -kInfinity;
    double max = -kInfinity, sum = 0.0;
    auto add = [&](double term) {
      if (term <= max) {
        sum += std::exp(term - max);
      } else {
        sum = sum * std::exp(max - term) + 1.0;
        max = term;
      }
    };
    if (shared_) {
      const Factor& f = factors_[0];
      std::array<double, kStackDims> y0{};  // L^{-1} (r - c_0)
      for (std::size_t i = 0; i < d_; ++i) {
        double y = 0.0;
        for (std::size_t k = 0; k <= i; ++k) y += f.l_inv[Tri(i, k)] * (reals[k] - centres_[k]);
        y0[i] = y;
      }
      for (std::size_t j = 0; j < NumComponents(); ++j) {
        const double* w = &whitened_[j * d_];
        double q = 0.0;
        for (std::size_t i = 0; i < d_; ++i) q += (y0[i] - w[i]) * (y0[i] - w[i]);
        add(log_weight_[j] - 0.5 * q -
            (truncate_ ? LogBoxMass(f, box_, reals, y0.data(), w) : 0.0));
      }
    } else {
      // L_j^{-1} (r - c_j), kept only for a truncated kernel's LogBoxMass.
      std::array<double, kStackDims> stack{};
      std::vector<double> heap(truncate_ && d_ > kStackDims ? d_ : 0);
      double* y = !truncate_ ? nullptr : d_ > kStackDims ? heap.data() : stack.data();
      for (std::size_t j = 0; j < NumComponents(); ++j) {
        const Factor& f = factors_[factor_of_[j]];
        const double* c = &centres_[j * d_];
        double q = 0.0;
        for (std::size_t i = 0; i < d_; ++i) {
          double v = 0.0;
          for (std::size_t k = 0; k <= i; ++k) v += f.l_inv[Tri(i, k)] * (reals[k] - c[k]);
          if (y) y[i] = v;
          q += v * v;
        }
        add(log_weight_[j] - 0.5 * q - (truncate_ ? LogBoxMass(f, box_, reals, y, nullptr) : 0.0));
      }
    }
    return max + std::log(sum);
  }

 private:
  // Dimensions up to this take LogDensity's shared-covariance path with its scratch on the stack.
  static constexpr std::size_t kStackDims = 64;

  std::size_t NumComponents() const { return cumulative_.size(); }

  std::size_t d_;
  RealsPrior prior_;  // a copy: the proposal may outlive the space
  Box box_;
  std::vector<Factor> factors_;
  std::vector<double> centres_;         // N x d
  std::vector<double> cumulative_;      // running sums of the weights
  std::vector<std::size_t> factor_of_;  // component -> factor
  std::vector<double> log_weight_;      // log w_j - (d/2) log 2 pi - log det L_j
  bool shared_ = false;
  std::vector<double> whitened_;  // shared_: L^{-1} (c_j - c_0), N x d
  bool truncate_ = false;         // each Gaussian truncated to the box (TruncateEachCoordinate)
};

// Wave 0 proposes from the prior itself: each real drawn from its own prior (a joint prior's at
// its first real), in order, so the importance weight p / q is 1 and every draw is inside the
// support.
class PriorProposal final : public ContinuousProposal {
 public:
  explicit PriorProposal(const ParameterSpace& space) : prior_(space.reals_prior()) {}
  void Sample(RandomStream& rng, std::span<double> reals) const override {
    prior_.Sample(rng, reals);
  }
  double LogDensity(std::span<const double> reals) const override {
    return prior_.LogDensity(reals);
  }

 private:
  RealsPrior prior_;  // a copy: the proposal may outlive the space
};

// The population's reals as an N x d matrix and its weights, checked against the space.
struct Particles {
  Eigen::MatrixXd r;  // N x d
  Eigen::VectorXd w;  // sums to 1
};

Particles ReadParticles(const Population& population, const ParameterSpace& space) {
  const auto n = population.size;
  const auto d = static_cast<std::size_t>(space.num_reals());
  COMBABC_CHECK(population.num_reals == d);
  COMBABC_CHECK(population.reals.size() == n * d && population.weights.size() == n);
  Particles p{Eigen::MatrixXd(n, d), Eigen::VectorXd(n)};
  double total = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double w = population.weights[i];
    COMBABC_CHECK(w >= 0.0 && std::isfinite(w));
    total += w;
    p.w(static_cast<Eigen::Index>(i)) = w;
    for (std::size_t k = 0; k < d; ++k) {
      p.r(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k)) = population.reals[i * d + k];
    }
  }
  COMBABC_CHECK(total > 0.0);
  p.w /= total;
  return p;
}

// Weighted covariance sum_i w_i (r_i - m)(r_i - m)^T with m = sum_i w_i r_i (w sums to 1; no
// small-sample correction, as in Beaumont et al. 2009), and the mean through `mean`.
Eigen::MatrixXd WeightedCovariance(const Eigen::MatrixXd& r,
                                   const Eigen::VectorXd& w,
                                   Eigen::RowVectorXd* mean) {
  *mean = w.transpose() * r;
  const Eigen::MatrixXd centred = r.rowwise() - *mean;
  return centred.transpose() * w.asDiagonal() * centred;
}

std::vector<double> RowMajor(const Eigen::MatrixXd& m) {
  std::vector<double> out;
  out.reserve(static_cast<std::size_t>(m.size()));
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    for (Eigen::Index k = 0; k < m.cols(); ++k) out.push_back(m(i, k));
  }
  return out;
}

class NormalKernel final : public ContinuousKernel {
 public:
  explicit NormalKernel(double scale) : scale_(scale) {}
  std::string name() const override { return ToString(ContinuousKernelKind::kNormal); }

  std::unique_ptr<ContinuousProposal> Fit(const Population& population,
                                          const ParameterSpace& space) const override {
    if (population.size == 0 || space.num_reals() == 0) return Prior(space);
    const Particles p = ReadParticles(population, space);
    Eigen::RowVectorXd mean;
    const Eigen::MatrixXd sigma = scale_ * WeightedCovariance(p.r, p.w, &mean);
    std::vector<Factor> factors = {Factorise(sigma, PriorSd(space))};
    const std::vector<double> weights(p.w.data(), p.w.data() + p.w.size());
    return std::make_unique<GaussianMixtureProposal>(space,
                                                     RowMajor(p.r),
                                                     weights,
                                                     std::move(factors),
                                                     std::vector<std::size_t>(weights.size()));
  }

 private:
  double scale_;
};

class OlcmKernel final : public ContinuousKernel {
 public:
  std::string name() const override { return ToString(ContinuousKernelKind::kOlcm); }

  std::unique_ptr<ContinuousProposal> Fit(const Population& population,
                                          const ParameterSpace& space) const override {
    if (population.size == 0 || space.num_reals() == 0) return Prior(space);
    const Particles p = ReadParticles(population, space);
    const auto n = static_cast<Eigen::Index>(population.size);
    // The particles within the next thresholds, with positive weight; all of them when there are
    // none (or the sampler did not mark any: within_next empty).
    COMBABC_CHECK(population.within_next.empty() ||
                  population.within_next.size() == population.size);
    std::vector<Eigen::Index> next;
    for (Eigen::Index i = 0; i < n; ++i) {
      const bool within =
          !population.within_next.empty() && population.within_next[static_cast<std::size_t>(i)];
      if (within && p.w(i) > 0.0) next.push_back(i);
    }
    if (next.empty()) {
      for (Eigen::Index i = 0; i < n; ++i) next.push_back(i);
    }
    Eigen::MatrixXd r_next(static_cast<Eigen::Index>(next.size()), p.r.cols());
    Eigen::VectorXd w_next(static_cast<Eigen::Index>(next.size()));
    for (std::size_t t = 0; t < next.size(); ++t) {
      r_next.row(static_cast<Eigen::Index>(t)) = p.r.row(next[t]);
      w_next(static_cast<Eigen::Index>(t)) = p.w(next[t]);
    }
    w_next /= w_next.sum();
    // sum_k w~_k (r_k - r_j)(r_k - r_j)^T = C + (m - r_j)(m - r_j)^T, with m and C the weighted
    // mean and covariance of the particles within the next thresholds: O(N d^2) for all j rather
    // than O(N^2 d^2).
    Eigen::RowVectorXd mean;
    const Eigen::MatrixXd cov = WeightedCovariance(r_next, w_next, &mean);
    const std::vector<double> prior_sd = PriorSd(space);
    std::vector<Factor> factors;
    std::vector<std::size_t> factor_of;
    for (Eigen::Index j = 0; j < n; ++j) {
      const Eigen::RowVectorXd offset = mean - p.r.row(j);
      factor_of.push_back(factors.size());
      factors.push_back(Factorise(cov + offset.transpose() * offset, prior_sd));
    }
    const std::vector<double> weights(p.w.data(), p.w.data() + p.w.size());
    return std::make_unique<GaussianMixtureProposal>(
        space, RowMajor(p.r), weights, std::move(factors), factor_of);
  }
};

}  // namespace

std::unique_ptr<ContinuousProposal> ContinuousKernel::Prior(const ParameterSpace& space) const {
  return std::make_unique<PriorProposal>(space);
}

std::unique_ptr<ContinuousKernel> MakeNormalKernel(double scale) {
  if (!(scale > 0.0) || !std::isfinite(scale)) {
    throw Error(ErrorKind::kConfig,
                "ProposalOptions::scale = " + Formatted(scale) + "; must be finite and > 0");
  }
  return std::make_unique<NormalKernel>(scale);
}

std::unique_ptr<ContinuousKernel> MakeOlcmKernel() { return std::make_unique<OlcmKernel>(); }

std::unique_ptr<ContinuousKernel> MakeContinuousKernel(const ProposalOptions& options) {
  switch (options.continuous) {
    case ContinuousKernelKind::kNormal:
      return MakeNormalKernel(options.scale);
    case ContinuousKernelKind::kOlcm:
      return MakeOlcmKernel();
  }
  throw Error(ErrorKind::kConfig,
              "ProposalOptions::continuous = " +
                  std::to_string(static_cast<int>(options.continuous)) + "; not a kernel kind");
}

}  // namespace combabc
