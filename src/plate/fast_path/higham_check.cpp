#include "plate/fast_path/higham_check.hpp"

#include <complex>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>

namespace combabc::plate {
namespace {

// One part (real or imaginary) of a section's matrix: the Schur complement of its interior onto
// its two end cross-sections, [left; right] (2 nc x 2 nc); false when the interior is not
// positive definite.
bool SectionSchur(const Plate& plate,
                  int section,
                  int intervals,
                  int nc,
                  bool imaginary,
                  double frequency_hz,
                  Eigen::MatrixXd* schur) {
  const int m = intervals;
  const int n_interior = (m - 1) * nc;
  // Local dofs cross-section after cross-section: the ends [0, nc) and [m nc, (m + 1) nc) are
  // kept; with no clamp fixed every other dof is interior.
  const auto kept = [&](int d) { return d < nc ? d : (d >= m * nc ? d - (m - 1) * nc : -1); };
  const auto inner = [&](int d) { return d >= nc && d < m * nc ? d - nc : -1; };
  const std::complex<double> mass = plate.MassCoefficient(frequency_hz);
  const double mass_part = imaginary ? mass.imag() : mass.real();
  const int nb = 2 * nc;
  Eigen::MatrixXd a_bb = Eigen::MatrixXd::Zero(nb, nb);
  Eigen::MatrixXd a_ib = Eigen::MatrixXd::Zero(n_interior, nb);
  std::vector<Eigen::Triplet<double>> triplets;
  ForEachSectionEntry(
      plate, section, m, [&](const ElementMatrices& e, int r, int c, int lr, int lc) {
        const double v = (imaginary ? e.stiffness_imag(r, c) : e.stiffness_real(r, c)) +
                         mass_part * e.mass_unit(r, c);
        const int rb = kept(lr);
        const int cb = kept(lc);
        const int ri = inner(lr);
        const int ci = inner(lc);
        if (rb >= 0 && cb >= 0) a_bb(rb, cb) += v;
        if (ri >= 0 && cb >= 0) a_ib(ri, cb) += v;
        if (ri >= 0 && ci >= 0) triplets.emplace_back(ri, ci, v);
      });
  *schur = a_bb;
  if (n_interior == 0) return true;
  Eigen::SparseMatrix<double> a_ii(n_interior, n_interior);
  a_ii.setFromTriplets(triplets.begin(), triplets.end());
  const Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> llt(a_ii);
  if (llt.info() != Eigen::Success) return false;
  *schur -= a_ib.transpose() * llt.solve(a_ib);
  return true;
}

}  // namespace

bool IsHighamSystem(const Plate& plate, const SectionLayout& layout, double frequency_hz) {
  const int num_sections = layout.num_sections();
  const int intervals = layout.intervals();
  const int nc = layout.nc();
  const auto mesh = [&](int s) { return layout.MeshOfSection(s); };
  for (const bool imaginary : {false, true}) {
    std::vector<Eigen::MatrixXd> schur(num_sections);
    for (int s = 0; s < num_sections; ++s) {
      if (mesh(s) != s) continue;
      if (!SectionSchur(plate, s, intervals, nc, imaginary, frequency_hz, &schur[s])) return false;
    }
    // The cross-sections' chain, block after block: the pivot block of cross-section c (its free
    // dofs) less what the elimination of c - 1 passed on, then what c passes on to c + 1.
    Eigen::MatrixXd carried = Eigen::MatrixXd::Zero(nc, nc);
    for (int c = 0; c <= num_sections; ++c) {
      Eigen::MatrixXd block = -carried;
      if (c > 0) block += schur[mesh(c - 1)].bottomRightCorner(nc, nc);
      if (c < num_sections) block += schur[mesh(c)].topLeftCorner(nc, nc);
      const std::vector<int>& free = layout.FreeDofs(c, false, false);
      const Eigen::MatrixXd pivot = block(free, free);
      const Eigen::LLT<Eigen::MatrixXd> llt(pivot);
      if (llt.info() != Eigen::Success) return false;
      if (c < num_sections) {
        const Eigen::MatrixXd coupling = schur[mesh(c)].topRightCorner(nc, nc)(free, Eigen::all);
        carried = coupling.transpose() * llt.solve(coupling);
      }
    }
  }
  return true;
}

}  // namespace combabc::plate
