#include "combabc/params/continuous_prior.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <limits>

#include "combabc/core/check.hpp"
#include "params/truncated_normal.hpp"

namespace combabc {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kLogSqrt2Pi = 0.91893853320467274178;  // log sqrt(2 pi)
// A truncated normal needs at least this much N(mean, sd^2) mass on [low, high]: below it the
// normaliser is not worth trusting and no sampler is efficient (ContinuousPrior::IsValid).
constexpr double kMinTruncatedMass = 1e-12;
// exp(x) overflows a double above ~709.78: a lognormal whose moments need exp(mean + sd^2) beyond
// this has no finite mean or variance in double precision.
constexpr double kMaxLogMoment = 700.0;

// Shortest text that reads back as the same double ("-1", "0.1", "inf").
std::string Num(double x) {
  std::array<char, 32> buf{};
  const auto result = std::to_chars(buf.data(), buf.data() + buf.size(), x);
  return {buf.data(), result.ptr};
}

StandardTruncation TruncateStandardised(const ContinuousPrior& p) {
  return TruncateStandardNormal((p.low - p.mean) / p.sd, (p.high - p.mean) / p.sd);
}

}  // namespace

bool ContinuousPrior::IsValid(std::string* why) const {
  ValidationError error;
  return ExplainValidation(IsValid(&error), error, why);
}

bool ContinuousPrior::IsValid(ValidationError* error) const {
  // No owner: the callers name the prior ("uniform prior: ", the config's key).
  auto fail = [&](const std::string& field, const std::string& value, const std::string& rest) {
    if (error) *error = {"", field, value, rest};
    return false;
  };
  auto finite = [&](const char* field, double value) {
    return std::isfinite(value) ? true : fail(field, Num(value), "must be finite");
  };
  auto ordered = [&] {
    return low < high ? true
                      : fail("low", Num(low) + " >= high = " + Num(high), "low must be below high");
  };
  if (kind == PriorKind::kJoint) {
    if (!ordered() || !finite("mean", mean) || !finite("sd", sd)) return false;
    return sd > 0.0 ? true : fail("sd", Num(sd), "must be > 0");
  }
  const bool uses_bounds = kind == PriorKind::kUniform || kind == PriorKind::kTruncatedNormal;
  const bool uses_normal = kind != PriorKind::kUniform;
  if (uses_bounds) {
    if (!finite("low", low) || !finite("high", high) || !ordered()) return false;
    if (!std::isfinite(high - low)) {
      return fail("high - low", Num(high - low), "the interval must have a finite width");
    }
  }
  if (uses_normal) {
    if (!finite("mean", mean) || !finite("sd", sd)) return false;
    if (!(sd > 0.0)) return fail("sd", Num(sd), "must be > 0");
  }
  switch (kind) {
    case PriorKind::kUniform:
    case PriorKind::kNormal:
    case PriorKind::kJoint:
      return true;
    case PriorKind::kLogNormal:
      if (mean + sd * sd >= kMaxLogMoment) {
        return fail("sd",
                    Num(sd) + " with mean = " + Num(mean),
                    "mean + sd^2 must be below " + Num(kMaxLogMoment) +
                        " for the lognormal's mean and variance to be finite");
      }
      return true;
    case PriorKind::kTruncatedNormal: {
      const double mass = TruncateStandardised(*this).mass;
      if (!(mass >= kMinTruncatedMass)) {
        return fail("low",
                    Num(low) + ", high = " + Num(high),
                    "N(mean = " + Num(mean) + ", sd = " + Num(sd) + ") has mass " + Num(mass) +
                        " on [low, high], must be >= " + Num(kMinTruncatedMass));
      }
      return true;
    }
  }
  return fail("kind", std::to_string(static_cast<int>(kind)), "not a prior kind");
}

bool ContinuousPrior::InSupport(double x) const {
  switch (kind) {
    case PriorKind::kUniform:
    case PriorKind::kTruncatedNormal:
      return x >= low && x <= high;  // false for NaN
    case PriorKind::kNormal:
      return std::isfinite(x);
    case PriorKind::kLogNormal:
      return x > 0.0 && x < kInf;
    case PriorKind::kJoint:
      return x >= low && x <= high && std::isfinite(x);
  }
  return false;
}

double ContinuousPrior::LogDensity(double x) const {
  if (!InSupport(x)) return -kInf;
  switch (kind) {
    case PriorKind::kUniform:
      return -std::log(high - low);
    case PriorKind::kNormal: {
      const double z = (x - mean) / sd;
      return -0.5 * z * z - std::log(sd) - kLogSqrt2Pi;
    }
    case PriorKind::kLogNormal: {
      const double log_x = std::log(x);
      const double z = (log_x - mean) / sd;
      return -0.5 * z * z - std::log(sd) - kLogSqrt2Pi - log_x;
    }
    case PriorKind::kTruncatedNormal: {
      const double z = (x - mean) / sd;
      return -0.5 * z * z - std::log(sd) - kLogSqrt2Pi - std::log(TruncateStandardised(*this).mass);
    }
    case PriorKind::kJoint:
      COMBABC_CHECK(kind != PriorKind::kJoint);  // ParameterSpace::LogPriorReals
  }
  return -kInf;
}

double ContinuousPrior::Sample(RandomStream& rng) const {
  switch (kind) {
    case PriorKind::kUniform:
      // Uniform() < 1, but low + w u may round up to high, which the closed support allows.
      return low + (high - low) * rng.Uniform();
    case PriorKind::kNormal:
      return mean + sd * rng.Normal();
    case PriorKind::kLogNormal:
      for (;;) {
        // exp under- or overflows only beyond ~37 sd for a valid prior; such a draw is not in
        // the (open) support, so draw again rather than return 0 or inf.
        const double x = std::exp(mean + sd * rng.Normal());
        if (x > 0.0 && x < kInf) return x;
      }
    case PriorKind::kTruncatedNormal: {
      const StandardTruncation t = TruncateStandardised(*this);
      const double z = SampleStandardTruncated(t.a, t.b, std::log(t.mass), rng);
      // z lies in [a, b]; mean + sd z may round a hair outside [low, high].
      return std::clamp(mean + sd * z, low, high);
    }
    case PriorKind::kJoint:
      COMBABC_CHECK(kind != PriorKind::kJoint);  // ParameterSpace::SampleReals
  }
  return std::numeric_limits<double>::quiet_NaN();
}

double ContinuousPrior::Mean() const {
  switch (kind) {
    case PriorKind::kUniform:
      return 0.5 * (low + high);
    case PriorKind::kNormal:
    case PriorKind::kJoint:
      return mean;
    case PriorKind::kLogNormal:
      return std::exp(mean + 0.5 * sd * sd);
    case PriorKind::kTruncatedNormal:
      return std::clamp(mean + sd * TruncateStandardised(*this).mean, low, high);
  }
  return std::numeric_limits<double>::quiet_NaN();
}

double ContinuousPrior::StandardDeviation() const {
  switch (kind) {
    case PriorKind::kUniform:
      return (high - low) / std::sqrt(12.0);
    case PriorKind::kNormal:
    case PriorKind::kJoint:
      return sd;
    case PriorKind::kLogNormal:
      // sqrt(exp(sd^2) - 1) exp(mean + sd^2 / 2); expm1 keeps small sd accurate.
      return std::sqrt(std::expm1(sd * sd)) * std::exp(mean + 0.5 * sd * sd);
    case PriorKind::kTruncatedNormal:
      return sd * std::sqrt(TruncateStandardised(*this).variance);
  }
  return std::numeric_limits<double>::quiet_NaN();
}

}  // namespace combabc
