// SectionCondensation to and from the precompute cache's payload (precompute_cache.hpp): every
// member Solve reads, as it stands after construction, except the layout, which the reader
// brings (the cache's key covers everything it is built from). A payload that does not describe a
// condensation consistent with that layout is refused (the caller rebuilds it), so no read can
// go out of bounds.
#include <memory>
#include <utility>

#include "plate/fast_path/precompute_cache.hpp"
#include "plate/fast_path/section_condensation.hpp"

namespace combabc::plate {
namespace {

void WriteLayout(ByteWriter& w, const OutputLayout& layout) {
  w.Value(static_cast<std::uint64_t>(layout.positions.size()));
  for (const std::vector<int>& p : layout.positions) w.Vector(p);
  w.Vector(layout.map_begin);
  w.Vector(layout.offset_begin);
}

OutputLayout ReadLayout(ByteReader& r) {
  OutputLayout layout;
  const auto sets = r.Value<std::uint64_t>();
  for (std::uint64_t s = 0; s < sets && !r.failed(); ++s) {
    layout.positions.push_back(r.Vector<int>());
  }
  layout.map_begin = r.Vector<int>();
  layout.offset_begin = r.Vector<int>();
  return layout;
}

}  // namespace

void SectionCondensation::Write(ByteWriter& w) const {
  w.Value(group_size_);
  w.Value(always_pivot_);
  w.Value(higham_);
  w.Value(static_cast<std::uint64_t>(group_pieces_.size()));
  for (const SolvePiece& p : group_pieces_) {
    for (const SplitMatrix* m :
         {&p.left_block, &p.right_block, &p.coupling_left, &p.coupling_right, &p.output_map}) {
      w.Dense(m->re);
      w.Dense(m->im);
    }
    w.Dense(p.load);
    w.Dense(p.output_offset);
    w.Value(p.left_size);
    w.Value(p.right_size);
    w.Value(p.singular);
  }
  w.Value(static_cast<std::uint64_t>(group_piece_index_.size()));
  for (const std::vector<int>& g : group_piece_index_) w.Vector(g);
  w.Value(static_cast<std::uint64_t>(group_layout_.size()));
  for (const OutputLayout& layout : group_layout_) WriteLayout(w, layout);
  w.Value(static_cast<std::uint64_t>(boundary_load_.size()));
  for (const Eigen::MatrixXcd& b : boundary_load_) w.Dense(b);
}

std::unique_ptr<SectionCondensation> SectionCondensation::Read(
    ByteReader& r, std::shared_ptr<const SectionLayout> section_layout, VectorKernels kernels) {
  std::unique_ptr<SectionCondensation> s(new SectionCondensation());
  s->layout_ = std::move(section_layout);
  s->group_size_ = r.Value<int>();
  s->always_pivot_ = r.Value<bool>();
  s->higham_ = r.Value<bool>();
  s->kernels_ = kernels;
  const auto pieces = r.Value<std::uint64_t>();
  for (std::uint64_t k = 0; k < pieces && !r.failed(); ++k) {
    SolvePiece p;
    for (SplitMatrix* m :
         {&p.left_block, &p.right_block, &p.coupling_left, &p.coupling_right, &p.output_map}) {
      m->re = r.Dense<Eigen::MatrixXd>();
      m->im = r.Dense<Eigen::MatrixXd>();
    }
    p.load = r.Dense<Eigen::MatrixXcd>();
    p.output_offset = r.Dense<Eigen::VectorXcd>();
    p.left_size = r.Value<int>();
    p.right_size = r.Value<int>();
    p.singular = r.Value<double>();
    s->group_pieces_.push_back(std::move(p));
  }
  const auto groups = r.Value<std::uint64_t>();
  for (std::uint64_t g = 0; g < groups && !r.failed(); ++g) {
    s->group_piece_index_.push_back(r.Vector<int>());
  }
  const auto layouts = r.Value<std::uint64_t>();
  for (std::uint64_t g = 0; g < layouts && !r.failed(); ++g) {
    s->group_layout_.push_back(ReadLayout(r));
  }
  const auto loads = r.Value<std::uint64_t>();
  for (std::uint64_t c = 0; c < loads && !r.failed(); ++c) {
    s->boundary_load_.push_back(r.Dense<Eigen::MatrixXcd>());
  }
  if (r.failed() || !r.at_end() || !s->Consistent()) return nullptr;
  return s;
}

// Every size and index Solve relies on, against the layout's dimensions.
bool SectionCondensation::Consistent() const {
  const int nc = layout_->nc();
  const int sections = layout_->num_sections();
  const int num_cases = layout_->num_cases();
  const OutputSets& sets = layout_->sets();
  if (group_size_ <= 0 || sections % group_size_ != 0 || group_size_ > 8) return false;
  const int groups = sections / group_size_;
  const auto cases = static_cast<std::size_t>(num_cases);
  const auto n_sets = sets.case_of_set.size();
  const auto is_block = [&](const SplitMatrix& m, Eigen::Index rows, Eigen::Index cols) {
    return m.re.rows() == rows && m.re.cols() == cols && m.im.rows() == rows && m.im.cols() == cols;
  };
  for (const SolvePiece& p : group_pieces_) {
    if ((p.left_size != 0 && p.left_size != nc) || (p.right_size != 0 && p.right_size != nc)) {
      return false;
    }
    const int nb = p.left_size + p.right_size;
    const Eigen::Index rank = p.coupling_left.re.cols();
    if (!is_block(p.left_block, p.left_size, p.left_size) ||
        !is_block(p.right_block, p.right_size, p.right_size) ||
        !is_block(p.coupling_left, p.left_size > 0 && p.right_size > 0 ? nc : 0, rank) ||
        !is_block(p.coupling_right, p.coupling_left.re.rows(), rank) || rank > nc ||
        p.output_map.re.cols() != nb || p.output_map.im.rows() != p.output_map.re.rows() ||
        p.output_map.im.cols() != nb || p.load.rows() != nb || p.load.cols() != num_cases) {
      return false;
    }
  }
  if (group_piece_index_.size() != static_cast<std::size_t>(groups) ||
      group_layout_.size() != static_cast<std::size_t>(groups)) {
    return false;
  }
  for (int g = 0; g < groups; ++g) {
    if (group_piece_index_[g].size() != std::size_t{1} << (2 * group_size_)) return false;
    const OutputLayout& layout = group_layout_[g];
    if (layout.positions.size() != n_sets || layout.map_begin.size() != n_sets + 1 ||
        layout.offset_begin.size() != cases + 1) {
      return false;
    }
    for (std::size_t set = 0; set < n_sets; ++set) {
      const int c = sets.case_of_set[set];
      const std::size_t outputs = sets.first_output[c + 1] - sets.first_output[c];
      if (layout.map_begin[set + 1] - layout.map_begin[set] !=
          static_cast<int>(layout.positions[set].size())) {
        return false;
      }
      for (int position : layout.positions[set]) {
        if (position < 0 || static_cast<std::size_t>(position) >= outputs) return false;
      }
    }
    for (std::size_t c = 0; c < cases; ++c) {
      const auto set = static_cast<std::size_t>(sets.set_of_case[c]);
      if (layout.offset_begin[c + 1] - layout.offset_begin[c] !=
          static_cast<int>(layout.positions[set].size())) {
        return false;
      }
    }
    if (layout.map_begin.front() != 0 || layout.offset_begin.front() != 0) return false;
    for (int index : group_piece_index_[g]) {
      if (index < 0 || static_cast<std::size_t>(index) >= group_pieces_.size()) return false;
      const SolvePiece& p = group_pieces_[static_cast<std::size_t>(index)];
      if (p.output_map.re.rows() != layout.map_rows() ||
          p.output_offset.size() != layout.offset_rows() || p.left_size != (g > 0 ? nc : 0) ||
          p.right_size != (g + 1 < groups ? nc : 0)) {
        return false;
      }
    }
  }
  if (boundary_load_.size() != static_cast<std::size_t>(sections) + 1) return false;
  for (const Eigen::MatrixXcd& b : boundary_load_) {
    if (b.rows() != nc || b.cols() != num_cases) return false;
  }
  return true;
}

}  // namespace combabc::plate
