#pragma once
// The folded normal error model of amplitude data (docs/algorithm.md, "Amplitude data"): an
// amplitude y = |mu + e|, e ~ N(0, sigma^2), has the density on y >= 0
//   f(y; mu, sigma) = (phi((y - mu) / sigma) + phi((y + mu) / sigma)) / sigma
// (Leone, Nelson & Nottingham 1961, "The folded normal distribution", Technometrics 3:543), even
// in mu: a signed model output reads as its magnitude.

namespace combabc {

// log f(y; mu, sigma) for y >= 0 and sigma > 0, without overflow or cancellation for any mu:
//   -log sigma - log(2 pi) / 2 - (y - |mu|)^2 / (2 sigma^2) + log1p(exp(-2 y |mu| / sigma^2)).
double FoldedNormalLogDensity(double y, double mu, double sigma);

// The mu >= 0 that maximises f(y; mu, sigma) over mu: 0 when y <= sigma (the two normal
// components' modes merge), else the root in (0, y] of mu = y tanh(y mu / sigma^2).
double FoldedNormalBestMean(double y, double sigma);

// -log(f(y; mu, sigma) / max_m f(y; m, sigma)) >= 0: one point's share of a folded_normal
// component's negative log-likelihood, 0 at the best mean (the normaliser c of Wilkinson's
// acceptance, as the gaussian component's zero residual).
double FoldedNormalDeviance(double y, double mu, double sigma);

}  // namespace combabc
