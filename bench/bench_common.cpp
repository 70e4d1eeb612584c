#include "bench/bench_common.hpp"

#include <atomic>
#include <cmath>
#include <numbers>
#include <optional>

#include "harness/input/mesh_generators.hpp"

namespace ricochet::bench {
namespace {

std::atomic<int> failures{0};

Model<2> build_plate_model(ElementKind element, MaterialKind material, int nx) {
  constexpr double young = 200e9, poisson = 0.3, density = 7800.0;
  constexpr PlaneMode plane = PlaneMode::stress;

  RectangleSpec spec;
  spec.width = spec.height = plate_side;
  spec.nx = spec.ny = nx;
  spec.triangles = element == ElementKind::t3;

  BodyInput<2> body;
  body.name = "plate";
  body.mesh = make_rectangle(spec);
  if (material == MaterialKind::st_venant_kirchhoff)
    body.material = StVenantKirchhoff::make(young, poisson, density, plane);
  else
    body.material = NeoHookean::make(young, poisson, density, plane);
  body.quad_element = element == ElementKind::q4_full_2x2 ? QuadElement::full_2x2
                                                           : QuadElement::one_point_hourglass;
  body.hourglass.form = element == ElementKind::q4_one_point_stiffness ? HourglassForm::stiffness
                                                                       : HourglassForm::viscous;
  body.thickness = 0.01;
  return build_model({body}, plane, Vec2::Zero());
}

}  // namespace

std::string_view element_name(ElementKind kind) {
  switch (kind) {
    case ElementKind::q4_full_2x2: return "q4_2x2";
    case ElementKind::q4_one_point_viscous: return "q4_one_point_viscous_hg";
    case ElementKind::q4_one_point_stiffness: return "q4_one_point_stiffness_hg";
    case ElementKind::t3: return "t3";
  }
  return "unknown";
}

std::string_view material_name(MaterialKind kind) {
  switch (kind) {
    case MaterialKind::st_venant_kirchhoff: return "st_venant_kirchhoff";
    case MaterialKind::neo_hookean: return "neo_hookean";
  }
  return "unknown";
}

const Model<2>& plate_model(ElementKind element, MaterialKind material, int nx) {
  struct Cached {
    ElementKind element;
    MaterialKind material;
    int nx = 0;
    Model<2> model;
  };
  static std::optional<Cached> cache;
  if (!cache || cache->element != element || cache->material != material || cache->nx != nx) {
    cache.reset();
    cache = Cached{element, material, nx, build_plate_model(element, material, nx)};
  }
  return cache->model;
}

Eigen::VectorXd plate_field(const Model<2>& model, int nx, double amplitude) {
  const double k = std::numbers::pi / plate_side;
  Eigen::VectorXd a(model.num_dofs());
  for (int n = 0; n < model.num_nodes(); ++n) {
    const double x = model.ref(0, n), y = model.ref(1, n);
    const int i = n % (nx + 1), j = n / (nx + 1);
    const double checker = (i + j) % 2 == 0 ? 1e-3 : -1e-3;
    a(2 * n) = amplitude * (std::sin(k * x) * std::cos(k * y) + checker);
    a(2 * n + 1) = amplitude * (std::cos(k * x) * std::sin(k * y) - checker);
  }
  return a;
}

void fail(benchmark::State& state, const std::string& message) {
  ++failures;
  state.SkipWithError(message.c_str());
}

int failure_count() { return failures.load(); }

}  // namespace ricochet::bench
