#pragma once
// Upper-tail probabilities of the chi-square and F distributions, for the fit checks' goodness of
// fit (docs/history.md, "Checks"). Neither the standard library nor Eigen has them: they are the
// regularised incomplete gamma and beta functions, by their series and continued fractions
// (Numerical Recipes, 3rd ed., 6.2 and 6.4); log Gamma by Lanczos, to 2e-10.

namespace combabc {

// P(X >= x) for X ~ chi-square with `dof` > 0 degrees of freedom (1 for x <= 0); NaN for a NaN or
// a dof <= 0.
double ChiSquareUpperTail(double x, double dof);

// P(F >= f) for F ~ F(d1, d2), d1, d2 > 0 (1 for f <= 0); NaN for a NaN or a dof <= 0.
double FUpperTail(double f, double d1, double d2);

}  // namespace combabc
