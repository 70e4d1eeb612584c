// The implicit scheme's iteration matrix for a Model<3> (tangent.hpp): the pattern of the 3D cells
// with three DOFs per node, and A = m_scale M + k_scale K_T + c_scale C assembled from the
// element matrices of element3d.hpp, one cell at a time.
#include <algorithm>
#include <cstddef>
#include <type_traits>
#include <variant>

#include "solver/forces/system_pattern.hpp"
#include "solver/forces/tangent.hpp"

namespace ricochet {
namespace {

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

// The element matrix k_scale K_T + c_scale C of cell e of a block into K (overwritten; f, the
// cell's forces, is scratch). One-point hexahedra: K_T = V B^T A B (+ the hourglass matrix,
// stiffness form), C = the hourglass matrix (viscous form); 2x2x2 hexahedra and tetrahedra have
// no damping matrix.
template <class Law>
void element_matrix(const Model<3>& model, const Hex8OnePointBlock& b, std::size_t e, const Law& law,
                    const double* u, const double* v, double k_scale, double c_scale, Hex8Nodes& f,
                    Hex8Matrix& K) {
  Hex8Matrix C;
  const Hex8OnePointGeom g = cell_geometry(model, b, e);
  hex8_one_point_stiffness<false>(g, law, gather<8>(u, b.conn[e]), gather<8>(v, b.conn[e]), f, K, C);
  K = k_scale * K + c_scale * C;
}
template <class Law>
void element_matrix(const Model<3>& model, const Hex8Block& b, std::size_t e, const Law& law, const double* u,
                    const double*, double k_scale, double, Hex8Nodes& f, Hex8Matrix& K) {
  const Hex8Geom g = cell_geometry(model, b, e);
  hex8_stiffness<false>(g, law, gather<8>(u, b.conn[e]), f, K);
  K *= k_scale;
}
template <class Law>
void element_matrix(const Model<3>& model, const Tet4Block& b, std::size_t e, const Law& law, const double* u,
                    const double*, double k_scale, double, Tet4Nodes& f, Tet4Matrix& K) {
  const Tet4Geom g = cell_geometry(model, b, e);
  tet4_stiffness<false>(g, law, gather<4>(u, b.conn[e]), f, K);
  K *= k_scale;
}

}  // namespace

template SystemMatrix make_system_matrix<3>(const Model<3>& model);

template <>
ForceTotals assemble_system(const Model<3>& model, const double* u, const double* v, double m_scale,
                            double k_scale, double c_scale, SystemMatrix& s, double* f_int, bool with_energy) {
  return assemble_with(model, m_scale, s, [&](double* val) {
    const int* slot = s.slots.data();
    for_each_cell_block(model, [&](const auto& b) {
      constexpr int N = std::decay_t<decltype(b)>::kNodes;
      std::visit(
          [&](const auto& law) {
            Nodes3<N> f;
            ElementMatrix3<N> K;
            for (std::size_t e = 0; e < b.conn.size(); ++e, slot += 9 * N * N) {
              element_matrix(model, b, e, law, u, v, k_scale, c_scale, f, K);
              scatter<N>(val, slot, K);
            }
          },
          b.material);
    });
    // The forces and totals of the 3D force pass, the ones the Newton residual uses.
    return internal_forces(model, u, v, f_int, with_energy);
  });
}

}  // namespace ricochet
