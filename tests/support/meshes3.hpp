// Shared set-up of the 3D model tests (test_model3.cpp, test_internal_forces3.cpp): the four
// laws, the element formulations, distorted boxes and smooth fields.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "harness/input/mesh_generators3.hpp"
#include "solver/model/model.hpp"

namespace ricochet::test3 {

constexpr double kYoung = 1e6;       // [Pa]
constexpr double kPoisson = 0.3;     // [-]
constexpr double kDensity = 1000.0;  // [kg/m^3]

struct Law {
  std::string name;
  Material3 m;
  double mu, lambda;  // small-strain Lame constants [Pa], from the parameters
  double scale() const { return mu + std::abs(lambda); }
};

inline std::vector<Law> all_laws() {
  const double lam = kYoung * kPoisson / ((1.0 + kPoisson) * (1.0 - 2.0 * kPoisson));
  const double mu = kYoung / (2.0 * (1.0 + kPoisson));
  const double c10 = 1.5e5, c01 = 0.5e5, kappa = 2e6, mr = 2.0 * (c10 + c01);
  return {{"StVenantKirchhoff", StVenantKirchhoff3::make(kYoung, kPoisson, kDensity), mu, lam},
          {"NeoHookean", NeoHookean3::make(kYoung, kPoisson, kDensity), mu, lam},
          {"BlatzKo", BlatzKo3::make(4e5, kDensity), 4e5, 4e5},
          {"MooneyRivlin", MooneyRivlin3::make(c10, c01, kappa, kDensity), mr, kappa - 2.0 * mr / 3.0}};
}

enum class Kind { hex8, hex8_viscous, hex8_stiffness, tet4 };
inline constexpr Kind kAllKinds[] = {Kind::hex8, Kind::hex8_viscous, Kind::hex8_stiffness, Kind::tet4};
inline const char* kind_name(Kind k) {
  switch (k) {
    case Kind::hex8: return "hex8 2x2x2";
    case Kind::hex8_viscous: return "hex8 1pt viscous";
    case Kind::hex8_stiffness: return "hex8 1pt stiffness";
    case Kind::tet4: return "tet4";
  }
  return "?";
}
inline bool is_tet(Kind k) { return k == Kind::tet4; }

inline BodyInput<3> body_of(Kind kind, Mesh3 mesh, const Material3& material, const std::string& name = "box") {
  BodyInput<3> b;
  b.name = name;
  b.mesh = std::move(mesh);
  b.material = material;
  b.hex_element = kind == Kind::hex8 ? HexElement::full_2x2x2 : HexElement::one_point_hourglass;
  b.hourglass.form = kind == Kind::hex8_stiffness ? HourglassForm::stiffness : HourglassForm::viscous;
  b.hourglass.coeff = 0.1;
  return b;
}

// A box of nx x ny x nz cells (hexahedra, or 6 tetrahedra each), its nodes moved by up to
// `jitter` of a cell side per coordinate (fixed seed), then mapped by X -> A X + c with A a
// rotation times an upper-triangular stretch and shear: no cell is a parallelepiped (jitter > 0)
// and no face is axis-aligned. The corner quality stays > 0.2 for jitter <= 0.15 (checked by the
// model builder's callers where it matters).
inline Mesh3 distorted_box(int nx, int ny, int nz, bool tets, double jitter, unsigned seed = 7) {
  BoxSpec spec;
  spec.size = Vec3(1.0, 0.8, 0.6);
  spec.nx = nx;
  spec.ny = ny;
  spec.nz = nz;
  spec.tetrahedra = tets;
  Mesh3 m = make_box(spec);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> d(-1.0, 1.0);
  const Vec3 h(spec.size.x() / nx, spec.size.y() / ny, spec.size.z() / nz);
  for (int p = 0; p < m.num_nodes(); ++p)
    for (int k = 0; k < 3; ++k) m.nodes(k, p) += jitter * h(k) * d(rng);
  Mat3 stretch;
  stretch << 1.2, 0.15, -0.1, 0.0, 0.9, 0.2, 0.0, 0.0, 1.1;
  const Mat3 a = Eigen::AngleAxisd(0.7, Vec3(1.0, -2.0, 0.5).normalized()).toRotationMatrix() * stretch;
  m.nodes = (a * m.nodes).colwise() + Vec3(0.3, -0.2, 0.1);
  return m;
}

// A smooth field of gradient ~ amplitude on the model's nodes (3n, interleaved).
inline Eigen::VectorXd smooth_field(const Model<3>& model, double amplitude) {
  Eigen::VectorXd a(model.num_dofs());
  for (int i = 0; i < model.num_nodes(); ++i) {
    const double x = model.ref(0, i), y = model.ref(1, i), z = model.ref(2, i);
    a(3 * i) = amplitude * (0.3 * x + 0.2 * std::sin(3.0 * y) + 0.1 * x * z);
    a(3 * i + 1) = amplitude * (-0.25 * y + 0.15 * std::cos(2.0 * z) + 0.2 * x * x);
    a(3 * i + 2) = amplitude * (0.1 * z + 0.3 * std::sin(2.0 * x + y) - 0.1 * y * z);
  }
  return a;
}

// A random field of entries in [-amplitude, amplitude] (fixed seed).
inline Eigen::VectorXd random_field(int n, double amplitude, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> d(-amplitude, amplitude);
  Eigen::VectorXd a(n);
  for (int i = 0; i < n; ++i) a(i) = d(rng);
  return a;
}

inline double max_abs(const Eigen::VectorXd& a) { return a.size() ? a.cwiseAbs().maxCoeff() : 0.0; }

}  // namespace ricochet::test3
