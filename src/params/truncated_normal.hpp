#pragma once
// N(0, 1) restricted to an interval [a, b]: its mass, moments and exact samplers. Shared by the
// truncated normal prior (continuous_prior.cpp), a joint normal prior truncated to its bounds
// (joint_prior.cpp) and the Gaussian kernels, which truncate each coordinate to the support
// (proposals/gaussian_factor.cpp).
#include "combabc/rng/random_stream.hpp"

namespace combabc {

// N(0, 1) on [a, b] (a < b; either end may be infinite): its mass Z = Phi(b) - Phi(a), and its
// mean and variance (Johnson, Kotz & Balakrishnan 1994, Sec. 10.1). The moments need Z > 0 in
// double precision (within ~37 of 0); LogStandardNormalMass has no such limit.
struct StandardTruncation {
  double a = 0.0, b = 0.0;
  double mass = 0.0;
  double mean = 0.0;
  double variance = 0.0;
};
StandardTruncation TruncateStandardNormal(double a, double b);

// log(Phi(b) - Phi(a)) to near full relative precision of Z, however far in a tail the interval
// lies (where Z itself underflows): -infinity only for an empty interval.
double LogStandardNormalMass(double a, double b);

// One exact draw of N(0, 1) restricted to [a, b] (a < b; either end may be infinite), whose log
// mass is `log_mass` (LogStandardNormalMass). By rejection (Robert 1995), so the number of
// draws from `rng` varies, but the expected number of tries is at most about 2 for any interval.
double SampleStandardTruncated(double a, double b, double log_mass, RandomStream& rng);

}  // namespace combabc
