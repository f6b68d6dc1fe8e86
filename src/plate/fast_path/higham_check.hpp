#pragma once
// Whether the system with every clamp free is a Higham matrix, A = B + iC with B and C (real,
// symmetric) positive definite: the class for which elimination without pivoting is provably
// stable (section_solve.cpp). Fixing dofs keeps a matrix in it, so this one system decides for
// every configuration.
#include "combabc/plate/assembly/plate.hpp"
#include "plate/fast_path/section_layout.hpp"

namespace combabc::plate {

// `plate` sectioned as `layout` says (only the short edges' masks apply: no clamp is fixed).
//
// A symmetric matrix is positive definite exactly when a diagonal block and its Schur complement
// are (Haynsworth). The sections' interiors do not couple to each other, so each part is checked
// as the interior of one section per distinct mesh (sections made of the same element matrices
// have the same interior), then the chain of cross-sections coupled through the sections' Schur
// complements: a few small factorizations instead of a sparse Cholesky of the whole strip.
bool IsHighamSystem(const Plate& plate, const SectionLayout& layout, double frequency_hz);

}  // namespace combabc::plate
