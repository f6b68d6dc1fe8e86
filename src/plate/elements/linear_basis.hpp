#pragma once
// The linear basis on [0, 1] of the bilinear elements (MITC4, RZT4): the value at s of the
// function that is 1 at end a (0 or 1) and 0 at the other, and its slope.

namespace combabc::plate {

inline double Linear(int a, double s) { return a == 0 ? 1.0 - s : s; }
inline double LinearSlope(int a) { return a == 0 ? -1.0 : 1.0; }

}  // namespace combabc::plate
