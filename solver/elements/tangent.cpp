#include "solver/elements/tangent.hpp"

#include "solver/elements/kinematics.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace ricochet {
namespace {

// The (2N x 2N) element matrix by displacement components: xx(I, K) is the entry of DOFs
// (I, x)-(K, x), xy(I, K) of (I, x)-(K, y), yy(I, K) of (I, y)-(K, y); by symmetry the entry
// (I, y)-(K, x) is xy(K, I), so three N x N blocks hold everything.
template <int N>
struct ElementMatrix {
  Eigen::Matrix<double, N, N> xx, xy, yy;
  void set_zero() {
    xx.setZero();
    xy.setZero();
    yy.setZero();
  }
};

// Adds w * d(vol dN/dX P^T)/du of one integration point: with the 2x2 blocks
// A_ik(J, L) = A(2i + J, 2k + L), block (i, k) of the element matrix is w dN A_ik dN^T.
template <int N>
inline void add_point(const Eigen::Matrix<double, N, 2>& dn, double w, const Eigen::Matrix4d& A,
                      ElementMatrix<N>& k) {
  const Eigen::Matrix<double, N, 2> wd = w * dn;
  const Eigen::Matrix<double, N, 2> txx = wd * A.topLeftCorner<2, 2>();
  const Eigen::Matrix<double, N, 2> txy = wd * A.topRightCorner<2, 2>();
  const Eigen::Matrix<double, N, 2> tyy = wd * A.bottomRightCorner<2, 2>();
  k.xx.noalias() += txx * dn.transpose();
  k.xy.noalias() += txy * dn.transpose();
  k.yy.noalias() += tyy * dn.transpose();
}

// Adds c g g^T to both displacement components (hourglass stiffness or damping).
template <int N>
inline void add_hourglass(const Eigen::Matrix<double, N, 1>& g, double c, ElementMatrix<N>& k) {
  const Eigen::Matrix<double, N, N> gg = (c * g) * g.transpose();
  k.xx += gg;
  k.yy += gg;
}

template <int N>
inline void scatter_matrix(double* val, const int* slot, const ElementMatrix<N>& k) {
  constexpr int D = 2 * N;
  for (int I = 0; I < N; ++I) {
    const int* r0 = slot + 2 * I * D;  // row of DOF (I, x)
    const int* r1 = r0 + D;            // row of DOF (I, y)
    for (int K = 0; K < N; ++K) {
      val[r0[2 * K]] += k.xx(I, K);
      val[r0[2 * K + 1]] += k.xy(I, K);
      val[r1[2 * K]] += k.xy(K, I);
      val[r1[2 * K + 1]] += k.yy(I, K);
    }
  }
}

struct Context {
  const double* u;
  const double* v;
  double k_scale, c_scale;
  double* val;
  double* f;
};

// Each kernel instantiation is its own function so the material law inlines into its loop
// (see internal_forces.cpp).
template <bool kEnergy, class Mat>
[[gnu::noinline]] void t3_system(const T3Block& b, const Mat& mat, const Context& x, const int* slots,
               ForceTotals& t) {
  double energy = 0.0, min_j = t.min_jacobian;
  ElementMatrix<3> k;
  for (std::size_t e = 0; e < b.conn.size(); ++e) {
    const T3Geom& g = b.geom[e];
    const Grad3 ue = gather<3>(x.u, b.conn[e]);
    const Mat2 F = deformation_gradient<3>(ue, g.dndx);
    min_j = std::min(min_j, F.determinant());
    Mat2 P;
    Eigen::Matrix4d A;
    mat.first_piola_and_tangent(F, P, A);
    scatter<3>(x.f, b.conn[e], g.vol * g.dndx * P.transpose());
    if constexpr (kEnergy) energy += g.vol * mat.energy_density(F);
    k.set_zero();
    add_point<3>(g.dndx, x.k_scale * g.vol, A, k);
    scatter_matrix<3>(x.val, slots + 36 * e, k);
  }
  t.strain_energy += energy;
  t.min_jacobian = min_j;
}

template <bool kEnergy, class Mat>
[[gnu::noinline]] void q4_full_system(const Q4FullBlock& b, const Mat& mat, const Context& x, const int* slots,
                    ForceTotals& t) {
  double energy = 0.0, min_j = t.min_jacobian;
  ElementMatrix<4> k;
  for (std::size_t e = 0; e < b.conn.size(); ++e) {
    const Q4FullGeom& g = b.geom[e];
    const Grad4 ue = gather<4>(x.u, b.conn[e]);
    Grad4 fe = Grad4::Zero();
    k.set_zero();
    for (int q = 0; q < 4; ++q) {
      const Mat2 F = deformation_gradient<4>(ue, g.dndx[q]);
      min_j = std::min(min_j, F.determinant());
      Mat2 P;
      Eigen::Matrix4d A;
      mat.first_piola_and_tangent(F, P, A);
      fe.noalias() += g.vol[q] * g.dndx[q] * P.transpose();
      if constexpr (kEnergy) energy += g.vol[q] * mat.energy_density(F);
      add_point<4>(g.dndx[q], x.k_scale * g.vol[q], A, k);
    }
    scatter<4>(x.f, b.conn[e], fe);
    scatter_matrix<4>(x.val, slots + 64 * e, k);
  }
  t.strain_energy += energy;
  t.min_jacobian = min_j;
}

template <bool kEnergy, bool kViscous, class Mat>
[[gnu::noinline]] void q4_hourglass_system(const Q4HourglassBlock& b, const Mat& mat, const Context& x,
                         const int* slots, ForceTotals& t) {
  double energy = 0.0, hg_energy = 0.0, hg_power = 0.0, min_j = t.min_jacobian;
  ElementMatrix<4> k;
  for (std::size_t e = 0; e < b.conn.size(); ++e) {
    const Q4HourglassGeom& g = b.geom[e];
    const Grad4 ue = gather<4>(x.u, b.conn[e]);
    const Mat2 F = deformation_gradient<4>(ue, g.dndx);
    min_j = std::min(min_j, F.determinant());
    Mat2 P;
    Eigen::Matrix4d A;
    mat.first_piola_and_tangent(F, P, A);
    Grad4 fe = g.vol * g.dndx * P.transpose();
    k.set_zero();
    add_point<4>(g.dndx, x.k_scale * g.vol, A, k);
    if constexpr (kViscous) {
      const Vec2 qdot = gather<4>(x.v, b.conn[e]).transpose() * g.gamma;
      const Vec2 Q = g.hourglass_coeff * qdot;
      fe.noalias() += g.gamma * Q.transpose();
      hg_power += Q.dot(qdot);
      add_hourglass<4>(g.gamma, x.c_scale * g.hourglass_coeff, k);
    } else {
      const Vec2 q = ue.transpose() * g.gamma;
      fe.noalias() += g.gamma * (g.hourglass_coeff * q).transpose();
      if constexpr (kEnergy) hg_energy += 0.5 * g.hourglass_coeff * q.squaredNorm();
      add_hourglass<4>(g.gamma, x.k_scale * g.hourglass_coeff, k);
    }
    scatter<4>(x.f, b.conn[e], fe);
    scatter_matrix<4>(x.val, slots + 64 * e, k);
    if constexpr (kEnergy) energy += g.vol * mat.energy_density(F);
  }
  t.strain_energy += energy;
  t.hourglass_energy += hg_energy;
  t.hourglass_power += hg_power;
  t.min_jacobian = min_j;
}

// Blocks in the order internal_forces visits them (hourglass Q4, full Q4, T3), so f_int sums in
// the same order; the slots are stored in Model order (q4_full, q4_hourglass, t3).
template <bool kEnergy>
void all_blocks(const Model& model, const Context& x, const int* slots, ForceTotals& t) {
  std::size_t off_full = 0, off_hg = 0, off_t3 = 0;
  for (const auto& b : model.q4_full) off_hg += 64 * b.conn.size();
  off_t3 = off_hg;
  for (const auto& b : model.q4_hourglass) off_t3 += 64 * b.conn.size();

  for (const auto& b : model.q4_hourglass) {
    std::visit(
        [&](const auto& mat) {
          if (b.form == HourglassForm::viscous)
            q4_hourglass_system<kEnergy, true>(b, mat, x, slots + off_hg, t);
          else
            q4_hourglass_system<kEnergy, false>(b, mat, x, slots + off_hg, t);
        },
        b.material);
    off_hg += 64 * b.conn.size();
  }
  for (const auto& b : model.q4_full) {
    std::visit([&](const auto& mat) { q4_full_system<kEnergy>(b, mat, x, slots + off_full, t); },
               b.material);
    off_full += 64 * b.conn.size();
  }
  for (const auto& b : model.t3) {
    std::visit([&](const auto& mat) { t3_system<kEnergy>(b, mat, x, slots + off_t3, t); },
               b.material);
    off_t3 += 36 * b.conn.size();
  }
}

// Appends the slots of one block's elements, row-major over element DOFs.
template <int N, class Block>
void block_slots(const Block& b, const SystemMatrix& s, std::vector<int>& slots) {
  const int* outer = s.matrix.outerIndexPtr();
  const int* inner = s.matrix.innerIndexPtr();
  for (const auto& c : b.conn)
    for (int a = 0; a < 2 * N; ++a) {
      const int row = 2 * c[a / 2] + a % 2;
      for (int bb = 0; bb < 2 * N; ++bb) {
        const int col = 2 * c[bb / 2] + bb % 2;
        const int* p = std::lower_bound(inner + outer[row], inner + outer[row + 1], col);
        slots.push_back(static_cast<int>(p - inner));
      }
    }
}

}  // namespace

SystemMatrix make_system_matrix(const Model& model) {
  const int n = model.num_nodes();
  // Node adjacency (each node with itself and every node it shares a cell with).
  std::vector<std::vector<int>> adj(n);
  for (int a = 0; a < n; ++a) adj[a].push_back(a);
  const auto add_cells = [&adj](const auto& conn) {
    for (const auto& c : conn)
      for (int a : c)
        for (int b : c) adj[a].push_back(b);
  };
  for (const auto& b : model.q4_full) add_cells(b.conn);
  for (const auto& b : model.q4_hourglass) add_cells(b.conn);
  for (const auto& b : model.t3) add_cells(b.conn);
  std::size_t nnz = 0;
  for (auto& l : adj) {
    std::sort(l.begin(), l.end());
    l.erase(std::unique(l.begin(), l.end()), l.end());
    nnz += 4 * l.size();
  }
  if (nnz > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    throw std::length_error("make_system_matrix: too many non-zeros for int indices");

  SystemMatrix s;
  s.matrix.resize(2 * n, 2 * n);  // compressed, empty
  s.matrix.resizeNonZeros(static_cast<Eigen::Index>(nnz));
  int* outer = s.matrix.outerIndexPtr();
  int* inner = s.matrix.innerIndexPtr();
  int pos = 0;
  for (int a = 0; a < n; ++a)
    for (int i = 0; i < 2; ++i) {
      outer[2 * a + i] = pos;
      for (int b : adj[a]) {
        inner[pos++] = 2 * b;
        inner[pos++] = 2 * b + 1;
      }
    }
  outer[2 * n] = pos;
  std::fill(s.matrix.valuePtr(), s.matrix.valuePtr() + nnz, 0.0);

  std::size_t num_slots = 0;
  for (const auto& b : model.q4_full) num_slots += 64 * b.conn.size();
  for (const auto& b : model.q4_hourglass) num_slots += 64 * b.conn.size();
  for (const auto& b : model.t3) num_slots += 36 * b.conn.size();
  s.slots.reserve(num_slots);
  for (const auto& b : model.q4_full) block_slots<4>(b, s, s.slots);
  for (const auto& b : model.q4_hourglass) block_slots<4>(b, s, s.slots);
  for (const auto& b : model.t3) block_slots<3>(b, s, s.slots);

  s.diagonal_slots.resize(2 * n);
  for (int d = 0; d < 2 * n; ++d)
    s.diagonal_slots[d] = static_cast<int>(
        std::lower_bound(inner + outer[d], inner + outer[d + 1], d) - inner);
  s.diagonal = Eigen::VectorXd::Zero(2 * n);
  return s;
}

ForceTotals assemble_system(const Model& model, const double* u, const double* v, double m_scale,
                            double k_scale, double c_scale, SystemMatrix& s, double* f_int,
                            bool with_energy) {
  const int ndof = model.num_dofs();
  double* val = s.matrix.valuePtr();
  std::fill(val, val + s.matrix.nonZeros(), 0.0);
  for (int d = 0; d < ndof; ++d) val[s.diagonal_slots[d]] = m_scale * model.mass[d];
  std::fill(f_int, f_int + ndof, 0.0);

  const Context x{u, v, k_scale, c_scale, val, f_int};
  ForceTotals t;
  if (with_energy)
    all_blocks<true>(model, x, s.slots.data(), t);
  else
    all_blocks<false>(model, x, s.slots.data(), t);

  for (int d = 0; d < ndof; ++d) s.diagonal[d] = val[s.diagonal_slots[d]];
  return t;
}

}  // namespace ricochet
