#include "solver/forces/tangent.hpp"

#include <algorithm>
#include <tuple>
#include <type_traits>

#include "solver/forces/element_kernels2.hpp"
#include "solver/forces/system_pattern.hpp"

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

// The assembly pass (element_kernels2.hpp): P and A = dP/dF in one evaluation at each point
// (first_piola_and_tangent), the element matrix k_scale K_T + c_scale C of each cell, scattered
// through `slots` (this block's, 4 N^2 per cell).
template <bool kEnergy_, int N>
struct SystemPass {
  static constexpr bool kEnergy = kEnergy_;
  double k_scale, c_scale;
  double* val;
  const int* slots;
  ElementMatrix<N> k;

  struct Response {
    Mat2 P;
    Eigen::Matrix4d A;
  };
  template <class Mat>
  EIGEN_ALWAYS_INLINE Response response(const Mat& mat, const Mat2& F) const {
    Response r;
    mat.first_piola_and_tangent(F, r.P, r.A);
    return r;
  }
  void begin_element() { k.set_zero(); }
  template <int kPoints, class Mat>
  void point(const Mat&, const Mat2&, double, const Response& r, const Eigen::Matrix<double, N, 2>& dn,
             double vol, int) {
    add_point<N>(dn, k_scale * vol, r.A, k);
  }
  // Hourglass stiffness (stiffness form) or damping (viscous form).
  void hourglass(const Eigen::Matrix<double, N, 1>& gamma, double c, bool viscous) {
    add_hourglass<N>(gamma, (viscous ? c_scale : k_scale) * c, k);
  }
  template <int kPoints>
  void end_element(std::size_t e, int) {
    scatter_matrix<N>(val, slots + 4 * N * N * e, k);
  }
  void finish(ForceTotals&) const {}
};

// Blocks in the order of for_each_block, as internal_forces sums f_int, and of the slots.
template <bool kEnergy>
void all_blocks(const Model<2>& model, const double* u, const double* v, double k_scale, double c_scale,
                double* val, double* f, const int* slots, ForceTotals& t) {
  for_each_block(model, [&](const auto& b, const auto& mat, auto viscous) {
    constexpr int N = std::tuple_size_v<typename std::decay_t<decltype(b.conn)>::value_type>;
    element_kernel<decltype(viscous)::value>(b, mat, u, v, DirectScatter{f},
                                             SystemPass<kEnergy, N>{k_scale, c_scale, val, slots, {}}, t);
    slots += 4 * N * N * b.conn.size();
  });
}

}  // namespace

template SystemMatrix make_system_matrix<2>(const Model<2>& model);

template <>
ForceTotals assemble_system(const Model<2>& model, const double* u, const double* v, double m_scale,
                            double k_scale, double c_scale, SystemMatrix& s, double* f_int, bool with_energy) {
  return assemble_with(model, m_scale, s, [&](double* val) {
    std::fill(f_int, f_int + model.num_dofs(), 0.0);
    ForceTotals t;
    if (with_energy)
      all_blocks<true>(model, u, v, k_scale, c_scale, val, f_int, s.slots.data(), t);
    else
      all_blocks<false>(model, u, v, k_scale, c_scale, val, f_int, s.slots.data(), t);
    return t;
  });
}

}  // namespace ricochet
