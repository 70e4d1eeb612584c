// The implicit scheme's iteration matrix for a Model3 (tangent.hpp): the pattern of the 3D cells
// with three DOFs per node, and A = m_scale M + k_scale K_T + c_scale C assembled from the
// element matrices of element3d.hpp, one cell at a time.
#include <algorithm>
#include <limits>
#include <stdexcept>
#include <variant>

#include "solver/elements/tangent.hpp"

namespace ricochet {
namespace {

// Appends the slots of one block's cells: for cell c the positions of the entries
// (3 c[a] + i, 3 c[b] + k), row-major over the element DOFs 3a + i.
template <class Block>
void block_slots3(const Block& b, const SystemMatrix& s, std::vector<int>& slots) {
  constexpr int N = Block::kNodes;
  const int* outer = s.matrix.outerIndexPtr();
  const int* inner = s.matrix.innerIndexPtr();
  for (const auto& c : b.conn)
    for (int r = 0; r < 3 * N; ++r) {
      const int row = 3 * c[r / 3] + r % 3;
      for (int q = 0; q < 3 * N; ++q) {
        const int col = 3 * c[q / 3] + q % 3;
        const int* p = std::lower_bound(inner + outer[row], inner + outer[row + 1], col);
        slots.push_back(static_cast<int>(p - inner));
      }
    }
}

// The displacement (or velocity) of cell e's corners, 3 x N.
template <int N, class Conn>
Nodes3<N> gather(const double* x, const Conn& c) {
  Nodes3<N> out;
  for (int a = 0; a < N; ++a)
    for (int i = 0; i < 3; ++i) out(i, a) = x[3 * c[a] + i];
  return out;
}

template <int N>
void scatter(double* val, const int* slot, const ElementMatrix3<N>& K) {
  for (int r = 0; r < 3 * N; ++r)
    for (int q = 0; q < 3 * N; ++q) val[slot[3 * N * r + q]] += K(r, q);
}

}  // namespace

SystemMatrix make_system_matrix(const Model3& model) {
  const int n = model.num_nodes();
  std::vector<std::vector<int>> adj(n);
  for (int a = 0; a < n; ++a) adj[a].push_back(a);
  for_each_cell_block(model, [&adj](const auto& b) {
    for (const auto& c : b.conn)
      for (int a : c)
        for (int q : c) adj[a].push_back(q);
  });
  std::size_t nnz = 0;
  for (auto& l : adj) {
    std::sort(l.begin(), l.end());
    l.erase(std::unique(l.begin(), l.end()), l.end());
    nnz += 9 * l.size();
  }
  if (nnz > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    throw std::length_error("make_system_matrix: too many non-zeros for int indices");

  SystemMatrix s;
  s.matrix.resize(3 * n, 3 * n);
  s.matrix.resizeNonZeros(static_cast<Eigen::Index>(nnz));
  int* outer = s.matrix.outerIndexPtr();
  int* inner = s.matrix.innerIndexPtr();
  int pos = 0;
  for (int a = 0; a < n; ++a)
    for (int i = 0; i < 3; ++i) {
      outer[3 * a + i] = pos;
      for (int b : adj[a])
        for (int k = 0; k < 3; ++k) inner[pos++] = 3 * b + k;
    }
  outer[3 * n] = pos;
  std::fill(s.matrix.valuePtr(), s.matrix.valuePtr() + nnz, 0.0);

  std::size_t num_slots = 0;
  for (const auto& b : model.hex8_hourglass) num_slots += 576 * b.conn.size();
  for (const auto& b : model.hex8_full) num_slots += 576 * b.conn.size();
  for (const auto& b : model.tet4) num_slots += 144 * b.conn.size();
  s.slots.reserve(num_slots);
  for (const auto& b : model.hex8_hourglass) block_slots3(b, s, s.slots);
  for (const auto& b : model.hex8_full) block_slots3(b, s, s.slots);
  for (const auto& b : model.tet4) block_slots3(b, s, s.slots);

  s.diagonal_slots.resize(3 * n);
  for (int d = 0; d < 3 * n; ++d)
    s.diagonal_slots[d] = static_cast<int>(std::lower_bound(inner + outer[d], inner + outer[d + 1], d) - inner);
  s.diagonal = Eigen::VectorXd::Zero(3 * n);
  return s;
}

ForceTotals assemble_system(const Model3& model, const double* u, const double* v, double m_scale,
                            double k_scale, double c_scale, SystemMatrix& s, double* f_int,
                            bool with_energy) {
  const int ndof = model.num_dofs();
  double* val = s.matrix.valuePtr();
  std::fill(val, val + s.matrix.nonZeros(), 0.0);
  for (int d = 0; d < ndof; ++d) val[s.diagonal_slots[d]] = m_scale * model.mass[d];

  const int* slot = s.slots.data();
  // One-point hexahedra: K_T = V B^T A B (+ the hourglass matrix, stiffness form), C = the
  // hourglass matrix (viscous form).
  for (const auto& b : model.hex8_hourglass)
    std::visit(
        [&](const auto& law) {
          Hex8Nodes f;
          Hex8Matrix K, C;
          for (std::size_t e = 0; e < b.conn.size(); ++e, slot += 576) {
            const Hex8OnePointGeom g = cell_geometry(model, b, e);
            hex8_one_point_stiffness<false>(g, law, gather<8>(u, b.conn[e]), gather<8>(v, b.conn[e]), f, K, C);
            K = k_scale * K + c_scale * C;
            scatter<8>(val, slot, K);
          }
        },
        b.material);
  for (const auto& b : model.hex8_full)
    std::visit(
        [&](const auto& law) {
          Hex8Nodes f;
          Hex8Matrix K;
          for (std::size_t e = 0; e < b.conn.size(); ++e, slot += 576) {
            const Hex8Geom g = cell_geometry(model, b, e);
            hex8_stiffness<false>(g, law, gather<8>(u, b.conn[e]), f, K);
            K *= k_scale;
            scatter<8>(val, slot, K);
          }
        },
        b.material);
  for (const auto& b : model.tet4)
    std::visit(
        [&](const auto& law) {
          Tet4Nodes f;
          Tet4Matrix K;
          for (std::size_t e = 0; e < b.conn.size(); ++e, slot += 144) {
            const Tet4Geom g = cell_geometry(model, b, e);
            tet4_stiffness<false>(g, law, gather<4>(u, b.conn[e]), f, K);
            K *= k_scale;
            scatter<4>(val, slot, K);
          }
        },
        b.material);
  for (int d = 0; d < ndof; ++d) s.diagonal[d] = val[s.diagonal_slots[d]];
  // The forces and totals of the 3D force pass, the ones the Newton residual uses.
  return internal_forces(model, u, v, f_int, with_energy);
}

}  // namespace ricochet
