// What the assembly of a SystemMatrix (tangent.hpp) does alike in either dimension: the fixed
// sparsity pattern, make_system_matrix(const Model<D>&) (index arithmetic only: no
// floating-point value depends on it), and the frame of every assembly, assemble_with().
// Instantiated in tangent.cpp (D = 2) and tangent3.cpp (D = 3).
#pragma once

#include <algorithm>
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <tuple>
#include <type_traits>
#include <vector>

#include "solver/forces/tangent.hpp"

namespace ricochet::system_pattern {

// The number of nodes of a block's cells (its conn holds std::array<int, N>).
template <class Block>
inline constexpr int kCellNodes = static_cast<int>(
    std::tuple_size_v<typename std::decay_t<decltype(std::declval<const Block&>().conn)>::value_type>);

// Appends the slots of one block's cells: for cell c the positions in s.matrix.valuePtr() of
// the entries (D c[a] + i, D c[b] + k), row-major over the element DOFs D a + i.
template <int D, class Block>
void block_slots(const Block& b, const SystemMatrix& s, std::vector<int>& slots) {
  constexpr int N = kCellNodes<Block>;
  const int* outer = s.matrix.outerIndexPtr();
  const int* inner = s.matrix.innerIndexPtr();
  for (const auto& c : b.conn)
    for (int r = 0; r < D * N; ++r) {
      const int row = D * c[r / D] + r % D;
      for (int q = 0; q < D * N; ++q) {
        const int col = D * c[q / D] + q % D;
        const int* p = std::lower_bound(inner + outer[row], inner + outer[row + 1], col);
        slots.push_back(static_cast<int>(p - inner));
      }
    }
}

}  // namespace ricochet::system_pattern
namespace ricochet {

// The SystemMatrix of a model (values zero, diagonal zero): the pattern of SystemMatrix (row
// D a + i holds the columns D b + k of every node b that shares a cell with node a, and node a's
// own), its slots in the order every pass visits the blocks (ModelBlocks<D>::kKinds), and its
// diagonal slots.
template <int D>
SystemMatrix make_system_matrix(const Model<D>& model) {
  using system_pattern::block_slots;
  using system_pattern::kCellNodes;
  const int n = model.num_nodes();
  auto for_each_block = [&model](auto&& fn) { for_each_cell_block(model, fn); };
  // Node adjacency (each node with itself and every node it shares a cell with).
  std::vector<std::vector<int>> adj(n);
  for (int a = 0; a < n; ++a) adj[a].push_back(a);
  std::size_t num_slots = 0;
  for_each_block([&](const auto& b) {
    constexpr int N = kCellNodes<std::decay_t<decltype(b)>>;
    for (const auto& c : b.conn)
      for (int a : c)
        for (int q : c) adj[a].push_back(q);
    num_slots += static_cast<std::size_t>(D * N) * (D * N) * b.conn.size();
  });
  std::size_t nnz = 0;
  for (auto& l : adj) {
    std::sort(l.begin(), l.end());
    l.erase(std::unique(l.begin(), l.end()), l.end());
    nnz += D * D * l.size();
  }
  if (nnz > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    throw std::length_error("make_system_matrix: too many non-zeros for int indices");

  SystemMatrix s;
  s.matrix.resize(D * n, D * n);  // compressed, empty
  s.matrix.resizeNonZeros(static_cast<Eigen::Index>(nnz));
  int* outer = s.matrix.outerIndexPtr();
  int* inner = s.matrix.innerIndexPtr();
  int pos = 0;
  for (int a = 0; a < n; ++a)
    for (int i = 0; i < D; ++i) {
      outer[D * a + i] = pos;
      for (int b : adj[a])
        for (int k = 0; k < D; ++k) inner[pos++] = D * b + k;
    }
  outer[D * n] = pos;
  std::fill(s.matrix.valuePtr(), s.matrix.valuePtr() + nnz, 0.0);

  s.slots.reserve(num_slots);
  for_each_block([&s](const auto& b) { block_slots<D>(b, s, s.slots); });

  s.diagonal_slots.resize(D * n);
  for (int d = 0; d < D * n; ++d)
    s.diagonal_slots[d] = static_cast<int>(std::lower_bound(inner + outer[d], inner + outer[d + 1], d) - inner);
  s.diagonal = Eigen::VectorXd::Zero(D * n);
  return s;
}

// A = m_scale M + (the element matrices): the values zeroed, the lumped mass on the diagonal,
// add_elements(values) adds the element matrices through the slots and returns the force
// pass's totals, then the diagonal is copied out (SystemMatrix::diagonal).
template <int D, class AddElements>
ForceTotals assemble_with(const Model<D>& model, double m_scale, SystemMatrix& s, AddElements&& add_elements) {
  const int ndof = model.num_dofs();
  double* val = s.matrix.valuePtr();
  std::fill(val, val + s.matrix.nonZeros(), 0.0);
  for (int d = 0; d < ndof; ++d) val[s.diagonal_slots[d]] = m_scale * model.mass[d];
  const ForceTotals t = add_elements(val);
  for (int d = 0; d < ndof; ++d) s.diagonal[d] = val[s.diagonal_slots[d]];
  return t;
}

}  // namespace ricochet
