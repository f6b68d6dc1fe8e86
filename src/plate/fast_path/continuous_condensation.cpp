#include "plate/fast_path/continuous_condensation.hpp"

#include <cmath>
#include <cstdint>
#include <limits>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseLU>

#include "combabc/core/check.hpp"
#include "combabc/core/error.hpp"

namespace combabc::plate {
namespace {

using Complex = std::complex<double>;

// A lower bound of the smallest eigenvalue of K x = lambda M x (K, M symmetric positive
// definite). Inverse iteration gives a Rayleigh quotient just above lambda_1; 0.9 of it is then
// proven a lower bound by Sylvester's law of inertia (K - bound M has a positive-pivot LDL^T iff
// no eigenvalue lies below the bound), halving it until the proof holds. Only the series' term
// count depends on it, and only logarithmically, so the 10 % margin costs at most a term.
double LowestEigenvalueBound(const Eigen::SparseMatrix<double>& k,
                             const Eigen::SparseMatrix<double>& m) {
  const Eigen::VectorXd scale = k.diagonal().cwiseAbs().cwiseSqrt().cwiseInverse();
  const Eigen::SparseMatrix<double> ks = scale.asDiagonal() * k * scale.asDiagonal();
  const Eigen::SparseMatrix<double> ms = scale.asDiagonal() * m * scale.asDiagonal();
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(ks);
  if (ldlt.info() != Eigen::Success || ldlt.vectorD().minCoeff() <= 0.0) {
    throw Error(ErrorKind::kSoftware, "continuous condensation: section interior not definite");
  }
  // Deterministic start with a component along every smooth shape.
  Eigen::VectorXd x(ks.rows());
  for (Eigen::Index r = 0; r < x.size(); ++r) {
    x(r) = 1.0 + 0.25 * std::sin(1.0 + 0.7 * static_cast<double>(r));
  }
  double rayleigh = std::numeric_limits<double>::infinity();
  for (int iteration = 0; iteration < 60; ++iteration) {
    const Eigen::VectorXd y = ldlt.solve(ms * x);
    x = y / std::sqrt(y.dot(ms * y));
    const double next = x.dot(ks * x);
    const bool converged = std::abs(next - rayleigh) <= 1e-6 * next;
    rayleigh = next;
    if (converged) break;
  }
  double bound = 0.9 * rayleigh;
  for (int attempt = 0; attempt < 200; ++attempt) {
    const Eigen::SparseMatrix<double> shifted = ks - bound * ms;
    ldlt.compute(shifted);
    if (ldlt.info() == Eigen::Success && ldlt.vectorD().minCoeff() > 0.0) return bound;
    bound *= 0.5;
  }
  throw Error(ErrorKind::kSoftware, "continuous condensation: no eigenvalue bound");
}

Eigen::MatrixXcd Symmetric(const Eigen::MatrixXcd& a) { return 0.5 * (a + a.transpose()); }

}  // namespace

int ContinuousCondensation::TermsFor(double q) {
  if (!(q > 0.0)) return 0;
  if (q > kMaxRatio) return -1;
  const int terms = static_cast<int>(std::ceil(std::log(kSeriesTol * (1.0 - q)) / std::log(q)));
  return std::max(terms, 1);
}

ContinuousCondensation::ContinuousCondensation(const Plate& plate,
                                               std::shared_ptr<const SectionLayout> section_layout,
                                               const Settings& settings)
    : layout_(std::move(section_layout)),
      own_loss_factors_(settings.own_loss_factors),
      always_pivot_(settings.always_pivot),
      kernels_(settings.kernels) {
  const SectionLayout& sections = *layout_;
  const int num_sections = sections.num_sections();
  const int nc = sections.nc();
  COMBABC_CHECK(plate.grid().nx() == num_sections * sections.intervals());
  // Distinct meshes: the same element lengths. Distinct sections: the same mesh, no interior
  // load in any case and outputs at the same relative positions in every output set (as
  // SectionCondensation shares pieces).
  for (int s = 0; s < num_sections; ++s) {
    int mesh = -1;
    for (std::size_t k = 0; k < mesh_section_.size() && mesh < 0; ++k) {
      if (sections.SameSpacing(s, mesh_section_[k])) mesh = static_cast<int>(k);
    }
    if (mesh < 0) {
      mesh = static_cast<int>(mesh_section_.size());
      mesh_section_.push_back(s);
    }
    mesh_kind_.push_back(mesh);
    int kind = -1;
    for (std::size_t k = 0; k < kind_section_.size() && kind < 0 && !sections.InteriorLoaded(s);
         ++k) {
      const int t = kind_section_[k];
      if (mesh_kind_[t] != mesh || sections.InteriorLoaded(t)) continue;
      if (sections.SameOutputPositions(s, t)) kind = static_cast<int>(k);
    }
    if (kind < 0) {
      kind = static_cast<int>(kind_section_.size());
      kind_section_.push_back(s);
    }
    kind_.push_back(kind);
  }
  states_.resize(mesh_section_.size() * 4);
  sections_.resize(kind_section_.size() * 4);
  for (int mesh = 0; mesh < static_cast<int>(mesh_section_.size()); ++mesh) {
    for (int state = 0; state < 4; ++state) {
      Precompute(plate, mesh, state);
    }
  }
  // Jacobi scaling of the cross-section dofs, as in SectionCondensation (CrossSectionScale), from
  // the static piece of section 0, both edges free.
  boundary_scale_ =
      CrossSectionScale(states_[static_cast<std::size_t>(mesh_kind_[0]) * 4].k_static, nc);
  Eigen::VectorXd s2(2 * nc);
  s2 << boundary_scale_, boundary_scale_;
  const auto both = [&](Eigen::MatrixXcd& a) { a = s2.asDiagonal() * a * s2.asDiagonal(); };
  for (StateData& sd : states_) {
    both(sd.k_static);
    both(sd.m_static);
    both(sd.k_bb);
    both(sd.m_bb);
    for (Eigen::MatrixXcd& t : sd.moments) both(t);
    sd.k_ib = sd.k_ib * s2.asDiagonal();
    sd.m_ib = sd.m_ib * s2.asDiagonal();
  }
  for (SectionData& sec : sections_) {
    sec.out_static = sec.out_static * s2.asDiagonal();
    for (Eigen::MatrixXcd& t : sec.out_terms) t = t * s2.asDiagonal();
    sec.r_b = sec.r_b * s2.asDiagonal();
    for (std::size_t l = 0; l < sec.loaded_cases.size(); ++l) {
      sec.load_static[l] = s2.asDiagonal() * sec.load_static[l];
      for (Eigen::VectorXcd& t : sec.load_terms[l]) t = s2.asDiagonal() * t;
    }
  }
  for (int c = 0; c <= num_sections; ++c) {
    boundary_load_.push_back(boundary_scale_.asDiagonal() * sections.BoundaryLoad(c));
  }
  BuildTables();
}

// The interior-interior entries of a section's matrices (complex stiffness and unit mass for the
// sparse LU, their real parts for the eigenvalue bound), gathered while assembling it.
struct ContinuousCondensation::InteriorTriplets {
  std::vector<Eigen::Triplet<Complex>> k;
  std::vector<Eigen::Triplet<Complex>> m;
  std::vector<Eigen::Triplet<double>> real;
  std::vector<Eigen::Triplet<double>> mass;
};

void ContinuousCondensation::Precompute(const Plate& plate, int mesh_kind, int state) {
  // Local dofs: boundary (index into [left; right]), interior (index into I), or fixed, as in
  // SectionCondensation::CondenseSections.
  DofClasses local;
  local.n_interior = layout_->ClassifySectionDofs(state, &local.boundary, &local.interior);
  InteriorTriplets triplets;
  AssembleState(plate, mesh_kind, state, local, &triplets);
  // The distinct sections of this mesh: their output rows r_I, r_B and interior load f_I.
  std::vector<int> kinds;
  for (int kind = 0; kind < static_cast<int>(kind_section_.size()); ++kind) {
    if (mesh_kind_[kind_section_[kind]] == mesh_kind) kinds.push_back(kind);
  }
  for (int kind : kinds) PrepareSection(plate, kind, state, local);
  StateData& sd = states_[static_cast<std::size_t>(mesh_kind) * 4 + state];
  const int n_interior = local.n_interior;
  for (int i = 0; i < n_interior; ++i) {
    if ((sd.k_ib.row(i).cwiseAbs().maxCoeff() != 0.0) ||
        (sd.m_ib.row(i).cwiseAbs().maxCoeff() != 0.0)) {
      sd.coupled.push_back(i);
    }
  }
  if (n_interior == 0) {  // one element per section: nothing to condense, C = K_BB + mu M_BB
    sd.lambda_bound = std::numeric_limits<double>::infinity();
    sd.k_static = sd.k_bb;
    sd.m_static = sd.m_bb;
    return;
  }
  CondenseInterior(mesh_kind, state, kinds, triplets);
}

// The section matrices split by physics: K_base (K_real, + i K_imag for the layers' own loss
// factors) and M_1, into the boundary blocks of the state and the interior triplets. Sections of
// one mesh have equal element matrices.
void ContinuousCondensation::AssembleState(const Plate& plate,
                                           int mesh_kind,
                                           int state,
                                           const DofClasses& local,
                                           InteriorTriplets* triplets) {
  const int nb = 2 * layout_->nc();
  const int m = layout_->intervals();
  const int n_interior = local.n_interior;
  const std::vector<int>& boundary_index = local.boundary;
  const std::vector<int>& interior_index = local.interior;
  StateData& sd = states_[static_cast<std::size_t>(mesh_kind) * 4 + state];
  const int section = mesh_section_[mesh_kind];
  sd.k_bb = Eigen::MatrixXcd::Zero(nb, nb);
  sd.m_bb = Eigen::MatrixXcd::Zero(nb, nb);
  sd.k_ib = Eigen::MatrixXcd::Zero(n_interior, nb);
  sd.m_ib = Eigen::MatrixXcd::Zero(n_interior, nb);
  ForEachSectionEntry(
      plate, section, m, [&](const ElementMatrices& e, int r, int c, int lr, int lc) {
        const double kr = e.stiffness_real(r, c);
        const Complex k(kr, own_loss_factors_ ? e.stiffness_imag(r, c) : 0.0);
        const double mm = e.mass_unit(r, c);
        const int rb = boundary_index[lr];
        const int cb = boundary_index[lc];
        const int ri = interior_index[lr];
        const int ci = interior_index[lc];
        if (rb >= 0 && cb >= 0) {
          sd.k_bb(rb, cb) += k;
          sd.m_bb(rb, cb) += mm;
        }
        if (ri >= 0 && cb >= 0) {
          sd.k_ib(ri, cb) += k;
          sd.m_ib(ri, cb) += mm;
        }
        if (ri >= 0 && ci >= 0) {
          triplets->k.emplace_back(ri, ci, k);
          triplets->m.emplace_back(ri, ci, mm);
          triplets->real.emplace_back(ri, ci, kr);
          triplets->mass.emplace_back(ri, ci, mm);
        }
      });
}

// Section `kind` of the mesh in `state`: its output rows r_I and r_B, the cases whose load reaches
// its interior (f_I), and the interior dofs each output set reads.
void ContinuousCondensation::PrepareSection(const Plate& plate,
                                            int kind,
                                            int state,
                                            const DofClasses& local) {
  const Eigen::MatrixXd& loads = layout_->loads();
  const std::vector<CaseOutputs>& outputs = layout_->outputs();
  const OutputSets& sets = layout_->sets();
  const int nc = layout_->nc();
  const int num_cases = layout_->num_cases();
  const int m = layout_->intervals();
  const int n_local = (m + 1) * nc;
  const int nb = 2 * nc;
  const int n_interior = local.n_interior;
  const std::vector<int>& boundary_index = local.boundary;
  const std::vector<int>& interior_index = local.interior;
  SectionData& sec = sections_[static_cast<std::size_t>(kind) * 4 + state];
  const int s = kind_section_[kind];
  const int s_offset = s * m * nc;
  const OutputLayout& layout = layout_->SectionOutputs(s);
  const auto n_out = static_cast<Eigen::Index>(layout.map_rows());
  sec.r_i = Eigen::MatrixXcd::Zero(n_out, n_interior);
  sec.r_b = Eigen::MatrixXcd::Zero(n_out, nb);
  for (int set = 0; set < sets.num_sets(); ++set) {
    const CaseOutputs& o = outputs[static_cast<std::size_t>(sets.case_of_set[set])];
    const std::vector<int>& positions = layout.positions[set];
    for (std::size_t t = 0; t < positions.size(); ++t) {
      const Eigen::Index k = layout.map_begin[set] + static_cast<Eigen::Index>(t);
      int dofs[kMaxElementDofs];
      ElementVector row;
      plate.InterpolationRow(o.x[positions[t]], o.y, dofs, &row);
      for (int q = 0; q < plate.element_dofs(); ++q) {
        const int d = dofs[q] - s_offset;
        COMBABC_CHECK(d >= 0 && d < n_local);
        if (boundary_index[d] >= 0) sec.r_b(k, boundary_index[d]) += row(q);
        if (interior_index[d] >= 0) sec.r_i(k, interior_index[d]) += row(q);
      }
    }
  }
  // The cases whose load reaches the interior, and their rows in the table (BuildTables).
  sec.loaded_cases.clear();
  sec.loaded_start.clear();
  std::vector<Eigen::VectorXcd> f;
  Eigen::Index next_row = n_out * nb;
  for (int c = 0; c < num_cases; ++c) {
    Eigen::VectorXcd f_c = Eigen::VectorXcd::Zero(n_interior);
    for (int d = 0; d < n_local; ++d) {
      if (interior_index[d] >= 0) f_c(interior_index[d]) = loads(s_offset + d, c);
    }
    if (n_interior == 0 || f_c.cwiseAbs().maxCoeff() == 0.0) continue;
    sec.loaded_cases.push_back(c);
    sec.loaded_start.push_back(next_row);
    next_row += nb + layout.rows_of_case(sets, c);
    f.push_back(std::move(f_c));
  }
  sec.f_i.resize(n_interior, static_cast<Eigen::Index>(f.size()));
  for (std::size_t l = 0; l < f.size(); ++l) sec.f_i.col(static_cast<Eigen::Index>(l)) = f[l];
  sec.map_rows = static_cast<int>(n_out);
  sec.read.assign(static_cast<std::size_t>(sets.num_sets()), {});
  for (int set = 0; set < sets.num_sets(); ++set) {
    const int first = layout.map_begin[set];
    const int rows = layout.map_begin[set + 1] - first;
    for (int i = 0; i < n_interior; ++i) {
      if (rows > 0 && sec.r_i.col(i).segment(first, rows).cwiseAbs().maxCoeff() != 0.0) {
        sec.read[set].push_back(i);
      }
    }
  }
  sec.out_static = sec.r_b;
}

// The static condensation of the interior (sparse LU of K_II) and the series terms in mu of the
// state and of each of its sections: moments, output maps, loads and offsets.
void ContinuousCondensation::CondenseInterior(int mesh_kind,
                                              int state,
                                              const std::vector<int>& kinds,
                                              const InteriorTriplets& triplets) {
  const OutputSets& sets = layout_->sets();
  StateData& sd = states_[static_cast<std::size_t>(mesh_kind) * 4 + state];
  const auto n_interior = static_cast<int>(sd.k_ib.rows());
  sd.k_ii.resize(n_interior, n_interior);
  sd.k_ii.setFromTriplets(triplets.k.begin(), triplets.k.end());
  sd.m_ii.resize(n_interior, n_interior);
  sd.m_ii.setFromTriplets(triplets.m.begin(), triplets.m.end());
  Eigen::SparseMatrix<double> k_real(n_interior, n_interior);
  k_real.setFromTriplets(triplets.real.begin(), triplets.real.end());
  Eigen::SparseMatrix<double> mass(n_interior, n_interior);
  mass.setFromTriplets(triplets.mass.begin(), triplets.mass.end());
  sd.lambda_bound = LowestEigenvalueBound(k_real, mass);

  // Jacobi-scaled sparse LU of K_II (complex symmetric: LU, as everywhere in the plate layer).
  const Eigen::VectorXd scale = sd.k_ii.diagonal().cwiseAbs().cwiseSqrt().cwiseInverse();
  Eigen::SparseMatrix<Complex> scaled = scale.asDiagonal() * sd.k_ii * scale.asDiagonal();
  scaled.makeCompressed();
  Eigen::SparseLU<Eigen::SparseMatrix<Complex>, Eigen::COLAMDOrdering<int>> lu;
  lu.compute(scaled);
  if (lu.info() != Eigen::Success) {
    throw Error(ErrorKind::kSoftware, "continuous condensation: singular interior matrix");
  }
  const auto solve = [&](const auto& b) -> Eigen::MatrixXcd {
    return scale.asDiagonal() * lu.solve((scale.asDiagonal() * b).eval());
  };
  const Eigen::MatrixXcd x0 = -solve(sd.k_ib);
  sd.k_static = Symmetric(sd.k_bb + sd.k_ib.transpose() * x0);
  const Eigen::MatrixXcd n = sd.m_ii * x0 + sd.m_ib;
  sd.m_static = Symmetric(sd.m_bb + sd.m_ib.transpose() * x0 + x0.transpose() * n);
  // Moments by the recursion Z_0 = K^{-1} N, Z_{k+1} = K^{-1} M Z_k; T_k = N^T Z_k.
  const int terms = TermsFor(kMaxRatio);
  // z_load[kind][loaded case]: each case's load as the vector it was with a single case.
  std::vector<std::vector<Eigen::MatrixXcd>> z_load(kinds.size());
  for (std::size_t i = 0; i < kinds.size(); ++i) {
    SectionData& sec = sections_[static_cast<std::size_t>(kinds[i]) * 4 + state];
    sec.out_static = sec.r_b + sec.r_i * x0;
    const std::size_t loaded = sec.loaded_cases.size();
    sec.load_static.resize(loaded);
    sec.load_terms.assign(loaded, {});
    sec.offset_terms.assign(loaded, {});
    for (std::size_t l = 0; l < loaded; ++l) {
      const Eigen::VectorXcd f = sec.f_i.col(static_cast<Eigen::Index>(l));
      sec.load_static[l] = x0.transpose() * f;
      z_load[i].push_back(solve(f));
    }
  }
  // The output rows of loaded case l of a section: its set's rows.
  const auto case_rows = [&](const SectionData& sec, int kind, std::size_t l) {
    const OutputLayout& layout = layout_->SectionOutputs(kind_section_[kind]);
    const int set = sets.set_of_case[sec.loaded_cases[l]];
    return sec.r_i.middleRows(layout.map_begin[set],
                              layout.map_begin[set + 1] - layout.map_begin[set]);
  };
  Eigen::MatrixXcd z = solve(n);
  for (int k = 0; k < terms; ++k) {
    sd.moments.push_back(Symmetric(n.transpose() * z));
    for (std::size_t i = 0; i < kinds.size(); ++i) {
      SectionData& sec = sections_[static_cast<std::size_t>(kinds[i]) * 4 + state];
      sec.out_terms.push_back(sec.r_i * z);
      for (std::size_t l = 0; l < sec.loaded_cases.size(); ++l) {
        Eigen::MatrixXcd& zl = z_load[i][l];
        sec.offset_terms[l].push_back(case_rows(sec, kinds[i], l) * zl);
        sec.load_terms[l].push_back(n.transpose() * zl);
        zl = solve(sd.m_ii * zl);
        if (k + 1 == terms) sec.offset_terms[l].push_back(case_rows(sec, kinds[i], l) * zl);
      }
    }
    if (k + 1 < terms) z = solve(sd.m_ii * z);
  }
}

void ContinuousCondensation::PackPiece(const Eigen::MatrixXcd& piece, Complex* out) const {
  const int nc = layout_->nc();
  Eigen::Index k = 0;
  for (int block = 0; block < 2; ++block) {
    const int o = block * nc;
    for (int j = 0; j < nc; ++j) {
      for (int i = j; i < nc; ++i) out[k++] = piece(o + i, o + j);
    }
  }
  for (int j = 0; j < nc; ++j) {
    for (int i = 0; i < nc; ++i) out[k++] = piece(i, nc + j);
  }
}

void ContinuousCondensation::BuildTables() {
  const int nc = layout_->nc();
  const int columns = TermsFor(kMaxRatio);
  const auto split =
      [](const Eigen::MatrixXcd& table, bool complex_base, StateData* sd, SectionData* sec) {
        Eigen::MatrixXd& re = sd != nullptr ? sd->table_re : sec->table_re;
        Eigen::MatrixXd& im = sd != nullptr ? sd->table_im : sec->table_im;
        re = table.real();
        if (complex_base) im = table.imag();
      };
  for (StateData& sd : states_) {
    const std::size_t count = 2 + sd.moments.size();
    Eigen::MatrixXcd table(PackedSize(), static_cast<Eigen::Index>(count));
    PackPiece(sd.k_static, table.col(0).data());
    PackPiece(-sd.m_static, table.col(1).data());
    for (std::size_t k = 0; k < sd.moments.size(); ++k) {
      PackPiece(-sd.moments[k], table.col(static_cast<Eigen::Index>(k) + 2).data());
    }
    split(table, own_loss_factors_, &sd, nullptr);
    sd.k_static.resize(0, 0);
    sd.m_static.resize(0, 0);
    sd.moments.clear();
  }
  for (SectionData& sec : sections_) {
    const Eigen::Index map_rows = sec.out_static.size();
    Eigen::Index rows = map_rows;
    for (const auto& offsets : sec.offset_terms) {
      rows += 2 * static_cast<Eigen::Index>(nc) + offsets.front().size();
    }
    const Eigen::Index count = sec.out_terms.empty() ? 1 : columns + 1;
    Eigen::MatrixXcd table = Eigen::MatrixXcd::Zero(rows, count);
    for (Eigen::Index j = 0; j < count; ++j) {
      const Eigen::MatrixXcd& map = j == 0 ? sec.out_static : sec.out_terms[j - 1];
      table.col(j).head(map_rows) = map.reshaped();
      for (std::size_t l = 0; l < sec.loaded_cases.size(); ++l) {
        const Eigen::VectorXcd& load = j == 0 ? sec.load_static[l] : sec.load_terms[l][j - 1];
        const Eigen::VectorXcd& offsets = sec.offset_terms[l][j];
        table.col(j).segment(sec.loaded_start[l], 2 * nc) = load;
        table.col(j).segment(sec.loaded_start[l] + 2 * static_cast<Eigen::Index>(nc),
                             offsets.size()) = offsets;
      }
    }
    split(table, own_loss_factors_, nullptr, &sec);
    sec.out_static.resize(0, 0);
    sec.out_terms.clear();
    sec.load_static.clear();
    sec.load_terms.clear();
    sec.offset_terms.clear();
  }
}

std::array<int, 4> ContinuousCondensation::SeriesTerms(std::complex<double> mu) const {
  std::array<int, 4> terms = {0, 0, 0, 0};
  for (std::size_t i = 0; i < states_.size(); ++i) {
    const int t = TermsFor(std::abs(mu) / states_[i].lambda_bound);
    int& slot = terms[i % 4];
    slot = (slot < 0 || t < 0) ? -1 : std::max(slot, t);
  }
  return terms;
}

std::size_t ContinuousCondensation::MemoryBytes() const {
  const auto bytes = [](const auto& a) {
    return sizeof(typename std::decay_t<decltype(a)>::Scalar) * static_cast<std::size_t>(a.size());
  };
  const auto sparse = [](const Eigen::SparseMatrix<Complex>& a) {
    return static_cast<std::size_t>(a.nonZeros()) * (sizeof(Complex) + sizeof(int)) +
           static_cast<std::size_t>(a.outerSize() + 1) * sizeof(int);
  };
  std::size_t total = 0;
  for (const StateData& sd : states_) {
    total += bytes(sd.table_re) + bytes(sd.table_im) + bytes(sd.k_ib) + bytes(sd.m_ib) +
             bytes(sd.k_bb) + bytes(sd.m_bb) + sparse(sd.k_ii) + sparse(sd.m_ii);
  }
  for (const SectionData& sec : sections_) {
    total += bytes(sec.table_re) + bytes(sec.table_im) + bytes(sec.r_i) + bytes(sec.r_b) +
             bytes(sec.f_i);
  }
  for (const auto& b : boundary_load_) total += bytes(b);
  return total;
}

}  // namespace combabc::plate
