#include "combabc/plate/assembly/plate.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <sstream>
#include <utility>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseLU>

#include "combabc/core/check.hpp"
#include "combabc/core/error.hpp"
#include "combabc/plate/elements/bfs_element.hpp"
#include "combabc/plate/elements/mitc4_element.hpp"
#include "combabc/plate/elements/mitc9_element.hpp"
#include "combabc/plate/elements/rzt_element.hpp"

namespace combabc::plate {
namespace {

// Grid line k of an axis (k counts node intervals, 2 per element at element order 2).
double At(const std::vector<double>& v, int k) { return v[static_cast<std::size_t>(k)]; }

// Index of the interval [v[k], v[k+1]] that contains t (clamped to the ends).
int Locate(const std::vector<double>& v, double t) {
  const auto it = std::upper_bound(v.begin(), v.end(), t);
  int k = static_cast<int>(it - v.begin()) - 1;
  return std::clamp(k, 0, static_cast<int>(v.size()) - 2);
}

void CheckAxis(const std::vector<double>& v, const char* name) {
  if (v.size() < 2) {
    throw Error(ErrorKind::kConfig, "a grid axis needs at least 2 nodes", "", 0, name);
  }
  for (std::size_t k = 1; k < v.size(); ++k) {
    if (!(v[k] > v[k - 1])) {
      throw Error(ErrorKind::kConfig, "grid coordinates must increase strictly", "", 0, name);
    }
  }
}

// The element family of each theory and order (element.hpp): its matrices, w shape functions and
// their integrals over a sub-rectangle.
ElementMatrices FamilyMatrices(
    PlateTheory theory, int order, double hx, double hy, const PlateSection& section) {
  switch (theory) {
    case PlateTheory::kKirchhoff:
      break;
    case PlateTheory::kFsdt:
      return order == 2 ? Mitc9ElementMatrices(hx, hy, section)
                        : Mitc4ElementMatrices(hx, hy, section);
    case PlateTheory::kRzt:
      return order == 2 ? Rzt9ElementMatrices(hx, hy, section)
                        : RztElementMatrices(hx, hy, section);
  }
  return ComputeElementMatrices(hx, hy, section.bending_real, section.bending_imag);
}

ElementVector FamilyShapeValues(
    PlateTheory theory, int order, double hx, double hy, double x, double y) {
  if (order == 2) return Quad9ShapeValues(DofsPerNode(theory), hx, hy, x, y);
  switch (theory) {
    case PlateTheory::kKirchhoff:
      break;
    case PlateTheory::kFsdt:
      return Mitc4ShapeValues(hx, hy, x, y);
    case PlateTheory::kRzt:
      return RztShapeValues(hx, hy, x, y);
  }
  return ShapeValues(hx, hy, x, y);
}

ElementVector FamilyShapeIntegral(PlateTheory theory,
                                  int order,
                                  double hx,
                                  double hy,
                                  double x0,
                                  double x1,
                                  double y0,
                                  double y1) {
  if (order == 2) return Quad9ShapeIntegral(DofsPerNode(theory), hx, hy, x0, x1, y0, y1);
  switch (theory) {
    case PlateTheory::kKirchhoff:
      break;
    case PlateTheory::kFsdt:
      return Mitc4ShapeIntegral(hx, hy, x0, x1, y0, y1);
    case PlateTheory::kRzt:
      return RztShapeIntegral(hx, hy, x0, x1, y0, y1);
  }
  return ShapeIntegral(hx, hy, x0, x1, y0, y1);
}

// Element order 2: an even number of intervals, each odd node at its element's midpoint (the
// 9-node element is formulated on a rectangle with its mid-side nodes there).
void CheckQuadraticAxis(const std::vector<double>& v, const char* name) {
  if ((v.size() - 1) % 2 != 0) {
    throw Error(ErrorKind::kConfig,
                "element order 2 needs an even number of grid intervals (2 per element)",
                "",
                0,
                name);
  }
  for (std::size_t k = 1; k + 1 < v.size(); k += 2) {
    if (std::abs(v[k] - 0.5 * (v[k - 1] + v[k + 1])) > 1e-9 * (v[k + 1] - v[k - 1])) {
      throw Error(ErrorKind::kConfig,
                  "element order 2 needs each mid-side node at its element's midpoint",
                  "",
                  0,
                  name);
    }
  }
}

}  // namespace

Grid UniformGrid(double length, double width, int nx, int ny) {
  COMBABC_CHECK(nx > 0 && ny > 0 && length > 0.0 && width > 0.0);
  Grid grid;
  for (int i = 0; i <= nx; ++i) grid.x.push_back(length * i / nx);
  for (int j = 0; j <= ny; ++j) grid.y.push_back(width * j / ny);
  return grid;
}

std::uint8_t SupportMask(Edge edge, Support support, PlateTheory theory) {
  const bool along_x = edge == Edge::kBottom || edge == Edge::kTop;
  switch (support) {
    case Support::kFree:
      return 0;
    case Support::kClamped:
      return static_cast<std::uint8_t>((1U << DofsPerNode(theory)) - 1U);
    case Support::kSimplySupported:
      // w = 0 along the edge also makes its tangential derivative vanish: w_x on y = const edges
      // (bit 1), w_y on x = const edges (bit 2). The normal slope and the twist stay free. In the
      // refined zigzag theory the tangential zigzag amplitude is held too (psi_x, bit 3, on
      // y = const; psi_y, bit 4, on x = const), as the tangential rotation is.
      if (theory == PlateTheory::kRzt) return along_x ? 0xB : 0x15;
      return along_x ? 0x3 : 0x5;
  }
  return 0;
}

Constraints::Constraints(const Grid& grid, PlateTheory theory)
    : x_(grid.x),
      y_(grid.y),
      theory_(theory),
      dofs_per_node_(DofsPerNode(theory)),
      all_dofs_(static_cast<std::uint8_t>((1U << dofs_per_node_) - 1U)),
      masks_(grid.x.size() * grid.y.size(), 0) {
  COMBABC_CHECK(dofs_per_node_ >= 1 && dofs_per_node_ <= kMaxDofsPerNode);
}

void Constraints::AddEdgeSupport(Edge edge, Support support) {
  const bool along_x = edge == Edge::kBottom || edge == Edge::kTop;
  const std::vector<double>& axis = along_x ? x_ : y_;
  AddEdgeSupport(edge, axis.front(), axis.back(), support);
}

void Constraints::AddEdgeSupport(Edge edge, double from, double to, Support support) {
  const std::uint8_t mask = SupportMask(edge, support, theory_) & all_dofs_;
  const int ny1 = static_cast<int>(y_.size());
  const bool along_x = edge == Edge::kBottom || edge == Edge::kTop;
  const std::vector<double>& axis = along_x ? x_ : y_;
  const double tol = 1e-9 * (axis.back() - axis.front());
  for (std::size_t k = 0; k < axis.size(); ++k) {
    if (axis[k] < from - tol || axis[k] > to + tol) continue;
    const int kk = static_cast<int>(k);
    int node = 0;
    switch (edge) {
      case Edge::kBottom:
        node = kk * ny1;
        break;
      case Edge::kTop:
        node = kk * ny1 + ny1 - 1;
        break;
      case Edge::kLeft:
        node = kk;
        break;
      case Edge::kRight:
        node = static_cast<int>(x_.size() - 1) * ny1 + kk;
        break;
    }
    masks_[node] |= mask;
  }
}

int Constraints::num_fixed() const {
  int n = 0;
  for (std::uint8_t m : masks_) n += std::popcount(m);
  return n;
}

SingularSystem::SingularSystem(double amplification)
    : Error(ErrorKind::kConfig,
            [&] {
              std::ostringstream text;
              text.precision(2);
              text << "the plate's system is singular or nearly so for this clamp configuration "
                      "(the solution is "
                   << amplification
                   << " times its load in scaled units): a rigid-body motion left free (no "
                      "foundation, no fixed edge, frequency 0) or an undamped resonance";
              return text.str();
            }()),
      amplification_(amplification) {}

Plate::Plate(Grid grid,
             PlateSection section,
             double foundation_stiffness,
             double foundation_loss_factor,
             PlateTheory theory,
             int element_order)
    : grid_(std::move(grid)),
      section_(std::move(section)),
      foundation_stiffness_(foundation_stiffness),
      foundation_loss_factor_(foundation_loss_factor),
      theory_(theory),
      order_(element_order) {
  CheckAxis(grid_.x, "Grid::x");
  CheckAxis(grid_.y, "Grid::y");
  if (order_ != 1 && order_ != 2) {
    throw Error(ErrorKind::kConfig, "element order must be 1 or 2", "", 0, "element_order");
  }
  if (order_ == 2) {
    if (theory_ == PlateTheory::kKirchhoff) {
      throw Error(ErrorKind::kConfig,
                  "element order 2 is for the shear theories (fsdt, rzt); kirchhoff has cubic "
                  "elements already",
                  "",
                  0,
                  "element_order");
    }
    CheckQuadraticAxis(grid_.x, "Grid::x");
    CheckQuadraticAxis(grid_.y, "Grid::y");
  }
  const int nx = num_elements_x();
  const int ny = num_elements_y();
  element_kind_.resize(static_cast<std::size_t>(nx) * ny);
  std::vector<std::pair<double, double>> sizes;
  for (int ex = 0; ex < nx; ++ex) {
    for (int ey = 0; ey < ny; ++ey) {
      const double hx = At(grid_.x, order_ * (ex + 1)) - At(grid_.x, order_ * ex);
      const double hy = At(grid_.y, order_ * (ey + 1)) - At(grid_.y, order_ * ey);
      // Elements of equal size (to 1e-12 relative) share one set of matrices.
      int kind = -1;
      for (std::size_t k = 0; k < sizes.size(); ++k) {
        if (std::abs(sizes[k].first - hx) <= 1e-12 * hx &&
            std::abs(sizes[k].second - hy) <= 1e-12 * hy) {
          kind = static_cast<int>(k);
          break;
        }
      }
      if (kind < 0) {
        kind = static_cast<int>(sizes.size());
        sizes.emplace_back(hx, hy);
        unique_elements_.push_back(FamilyMatrices(theory_, order_, hx, hy, section_));
      }
      element_kind_[ex * ny + ey] = kind;
    }
  }
}

int Plate::ElementDof(int ex, int ey, int local) const {
  const int n = dofs_per_node();
  const int node = local / n;
  const int a = node % (order_ + 1);
  const int b = node / (order_ + 1);
  return n * Node(order_ * ex + a, order_ * ey + b) + local % n;
}

std::complex<double> Plate::MassCoefficient(double frequency_hz) const {
  const double omega = 2.0 * M_PI * frequency_hz;
  return {foundation_stiffness_ - omega * omega * section_.mass_per_area,
          foundation_stiffness_ * foundation_loss_factor_};
}

Eigen::VectorXd Plate::LoadVector(const Load& load) const {
  Eigen::VectorXd f = Eigen::VectorXd::Zero(num_dofs());
  const double length = grid_.x.back();
  const double width = grid_.y.back();
  if (load.patch_length <= 0.0 || load.patch_width <= 0.0) {
    int dofs[kMaxElementDofs];
    ElementVector row;
    InterpolationRow(load.x, load.y, dofs, &row);
    for (int k = 0; k < element_dofs(); ++k) f(dofs[k]) += load.force * row(k);
    return f;
  }
  const double x0 = std::max(0.0, load.x - 0.5 * load.patch_length);
  const double x1 = std::min(length, load.x + 0.5 * load.patch_length);
  const double y0 = std::max(0.0, load.y - 0.5 * load.patch_width);
  const double y1 = std::min(width, load.y + 0.5 * load.patch_width);
  COMBABC_CHECK(x1 > x0 && y1 > y0);
  const double pressure = load.force / ((x1 - x0) * (y1 - y0));
  const int p = order_;
  for (int ex = 0; ex < num_elements_x(); ++ex) {
    const double ax = std::max(x0, At(grid_.x, p * ex));
    const double bx = std::min(x1, At(grid_.x, p * (ex + 1)));
    if (bx <= ax) continue;
    for (int ey = 0; ey < num_elements_y(); ++ey) {
      const double ay = std::max(y0, At(grid_.y, p * ey));
      const double by = std::min(y1, At(grid_.y, p * (ey + 1)));
      if (by <= ay) continue;
      const double hx = At(grid_.x, p * (ex + 1)) - At(grid_.x, p * ex);
      const double hy = At(grid_.y, p * (ey + 1)) - At(grid_.y, p * ey);
      const double lx0 = ax - At(grid_.x, p * ex);
      const double lx1 = bx - At(grid_.x, p * ex);
      const double ly0 = ay - At(grid_.y, p * ey);
      const double ly1 = by - At(grid_.y, p * ey);
      const ElementVector fe = FamilyShapeIntegral(theory_, p, hx, hy, lx0, lx1, ly0, ly1);
      for (int k = 0; k < element_dofs(); ++k) f(ElementDof(ex, ey, k)) += pressure * fe(k);
    }
  }
  return f;
}

Eigen::SparseMatrix<std::complex<double>> Plate::DynamicStiffness(
    const Constraints& constraints, double frequency_hz, std::vector<int>* free_dofs) const {
  // Constraints built for another dof layout (Plate::NewConstraints gives the right one).
  COMBABC_CHECK(constraints.dofs_per_node() == dofs_per_node());
  std::vector<int> map(num_dofs(), -1);
  free_dofs->clear();
  for (int d = 0; d < num_dofs(); ++d) {
    if (!constraints.IsFixed(d)) {
      map[d] = static_cast<int>(free_dofs->size());
      free_dofs->push_back(d);
    }
  }
  const std::complex<double> mass_coefficient = MassCoefficient(frequency_hz);
  const std::complex<double> i_unit(0.0, 1.0);
  std::vector<Eigen::Triplet<std::complex<double>>> triplets;
  const int ne = element_dofs();
  triplets.reserve(static_cast<std::size_t>(num_elements_x()) * num_elements_y() * ne * ne);
  for (int ex = 0; ex < num_elements_x(); ++ex) {
    for (int ey = 0; ey < num_elements_y(); ++ey) {
      const ElementMatrices& e = Element(ex, ey);
      int global[kMaxElementDofs];
      for (int k = 0; k < ne; ++k) global[k] = map[ElementDof(ex, ey, k)];
      for (int c = 0; c < ne; ++c) {
        if (global[c] < 0) continue;
        for (int r = 0; r < ne; ++r) {
          if (global[r] < 0) continue;
          triplets.emplace_back(global[r],
                                global[c],
                                e.stiffness_real(r, c) + i_unit * e.stiffness_imag(r, c) +
                                    mass_coefficient * e.mass_unit(r, c));
        }
      }
    }
  }
  const int n = static_cast<int>(free_dofs->size());
  Eigen::SparseMatrix<std::complex<double>> a(n, n);
  a.setFromTriplets(triplets.begin(), triplets.end());
  return a;
}

Eigen::VectorXd Plate::SolveStatic(const Constraints& constraints, const Load& load) const {
  std::vector<int> free_dofs;
  // Static: zero frequency; keep only the real parts (no damping in a static solve).
  const Eigen::SparseMatrix<double> a = DynamicStiffness(constraints, 0.0, &free_dofs).real();
  const Eigen::VectorXd f_all = LoadVector(load);
  Eigen::VectorXd f(static_cast<Eigen::Index>(free_dofs.size()));
  for (std::size_t k = 0; k < free_dofs.size(); ++k) {
    f(static_cast<Eigen::Index>(k)) = f_all(free_dofs[k]);
  }
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(a);  // real SPD: LDL^T is right here
  if (solver.info() != Eigen::Success || (solver.vectorD().array() <= 0.0).any()) {
    throw Error(ErrorKind::kConfig, "static stiffness is singular: the plate is not supported");
  }
  const Eigen::VectorXd x = solver.solve(f);
  Eigen::VectorXd u = Eigen::VectorXd::Zero(num_dofs());
  for (std::size_t k = 0; k < free_dofs.size(); ++k) {
    u(free_dofs[k]) = x(static_cast<Eigen::Index>(k));
  }
  return u;
}

Eigen::VectorXcd Plate::SolveHarmonic(const Constraints& constraints,
                                      const Load& load,
                                      double frequency_hz) const {
  return SolveHarmonic(constraints, LoadVector(load), frequency_hz);
}

Eigen::VectorXcd Plate::SolveHarmonic(const Constraints& constraints,
                                      const Eigen::VectorXd& load_vector,
                                      double frequency_hz) const {
  std::vector<int> free_dofs;
  Eigen::SparseMatrix<std::complex<double>> a =
      DynamicStiffness(constraints, frequency_hz, &free_dofs);
  a.makeCompressed();
  Eigen::VectorXcd f(static_cast<Eigen::Index>(free_dofs.size()));
  for (std::size_t k = 0; k < free_dofs.size(); ++k) {
    f(static_cast<Eigen::Index>(k)) = load_vector(free_dofs[k]);
  }
  // Symmetric Jacobi scaling: the BFS dofs w, w_x, w_y, w_xy carry different units, so on graded
  // meshes the unscaled matrix is badly conditioned; S A S with S = |diag A|^{-1/2} is not.
  const Eigen::VectorXd scale = a.diagonal().cwiseAbs().cwiseSqrt().cwiseInverse();
  a = scale.asDiagonal() * a * scale.asDiagonal();
  a.makeCompressed();
  Eigen::SparseLU<Eigen::SparseMatrix<std::complex<double>>, Eigen::COLAMDOrdering<int>> solver;
  solver.compute(a);
  if (solver.info() != Eigen::Success) {
    throw Error(ErrorKind::kSoftware,
                "sparse LU of the dynamic stiffness failed: " + solver.lastErrorMessage());
  }
  const Eigen::VectorXcd scaled_f = scale.asDiagonal() * f;
  Eigen::VectorXcd y = solver.solve(scaled_f);
  // Two steps of iterative refinement: cheap next to the factorization, and they take the
  // reference path to round-off even on strongly graded meshes.
  for (int step = 0; step < 2; ++step) {
    const Eigen::VectorXcd residual = scaled_f - a * y;
    y += solver.solve(residual);
  }
  // Singular or nearly so (plate.hpp, kMaxResidual): the refined solution does not reproduce its
  // load. Not the amplification of the fast paths: on fine graded meshes a regular system's
  // scaled solution grows far past kMaxAmplification with the mesh alone.
  const double load = scaled_f.cwiseAbs().maxCoeff();
  const double residual = (scaled_f - a * y).cwiseAbs().maxCoeff();
  if (!(residual <= kMaxResidual * load)) {
    throw SingularSystem(y.cwiseAbs().maxCoeff() / load);
  }
  const Eigen::VectorXcd x = scale.asDiagonal() * y;
  Eigen::VectorXcd u = Eigen::VectorXcd::Zero(num_dofs());
  for (std::size_t k = 0; k < free_dofs.size(); ++k) {
    u(free_dofs[k]) = x(static_cast<Eigen::Index>(k));
  }
  return u;
}

void Plate::InterpolationRow(double x,
                             double y,
                             int dofs[kMaxElementDofs],
                             ElementVector* row) const {
  const int p = order_;
  const int ex = Locate(grid_.x, x) / p;
  const int ey = Locate(grid_.y, y) / p;
  const double hx = At(grid_.x, p * (ex + 1)) - At(grid_.x, p * ex);
  const double hy = At(grid_.y, p * (ey + 1)) - At(grid_.y, p * ey);
  *row = FamilyShapeValues(theory_, p, hx, hy, x - At(grid_.x, p * ex), y - At(grid_.y, p * ey));
  for (int k = 0; k < element_dofs(); ++k) dofs[k] = ElementDof(ex, ey, k);
}

double Plate::Deflection(const Eigen::VectorXd& u, double x, double y) const {
  int dofs[kMaxElementDofs];
  ElementVector row;
  InterpolationRow(x, y, dofs, &row);
  double w = 0.0;
  for (int k = 0; k < element_dofs(); ++k) w += row(k) * u(dofs[k]);
  return w;
}

std::complex<double> Plate::Deflection(const Eigen::VectorXcd& u, double x, double y) const {
  int dofs[kMaxElementDofs];
  ElementVector row;
  InterpolationRow(x, y, dofs, &row);
  std::complex<double> w = 0.0;
  for (int k = 0; k < element_dofs(); ++k) w += row(k) * u(dofs[k]);
  return w;
}

}  // namespace combabc::plate
