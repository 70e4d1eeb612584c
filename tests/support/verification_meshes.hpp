// Small meshes and models for the solver verification tests (test_elements, test_explicit,
// test_no_allocation). Built by hand so the tests depend on the solver only.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "solver/model/model.hpp"

namespace ricochet::verification {

// The element formulations under test.
enum class ElementKind { q4_full, q4_viscous, q4_stiffness, t3 };

inline const char* element_name(ElementKind k) {
  switch (k) {
    case ElementKind::q4_full: return "Q4 2x2";
    case ElementKind::q4_viscous: return "Q4 1pt viscous HG";
    case ElementKind::q4_stiffness: return "Q4 1pt stiffness HG";
    case ElementKind::t3: return "T3";
  }
  return "?";
}

inline const std::vector<ElementKind>& all_element_kinds() {
  static const std::vector<ElementKind> kinds = {ElementKind::q4_full, ElementKind::q4_viscous,
                                                 ElementKind::q4_stiffness, ElementKind::t3};
  return kinds;
}

// A width x height rectangle of nx x ny cells, node (i, j) at index j*(nx+1) + i. Interior
// nodes are moved by up to `distortion` of the cell size in a fixed irregular pattern, which
// keeps every quad convex for distortion < 0.25. With `triangles` every quad is split along
// the diagonal that alternates with (i + j), giving T3 cells.
inline Mesh grid_mesh(double width, double height, int nx, int ny, double distortion,
                      bool triangles) {
  Mesh m;
  m.nodes.resize(2, (nx + 1) * (ny + 1));
  const double hx = width / nx, hy = height / ny;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      const int k = j * (nx + 1) + i;
      double x = i * hx, y = j * hy;
      if (i > 0 && i < nx && j > 0 && j < ny) {
        x += distortion * hx * std::sin(1.7 * k + 0.3);
        y += distortion * hy * std::cos(2.3 * k + 1.1);
      }
      m.nodes(0, k) = x;
      m.nodes(1, k) = y;
    }
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int a = j * (nx + 1) + i, b = a + 1, c = b + nx + 1, d = a + nx + 1;
      if (!triangles) {
        m.quads.push_back({a, b, c, d});
      } else if ((i + j) % 2 == 0) {
        m.tris.push_back({a, b, c});
        m.tris.push_back({a, c, d});
      } else {
        m.tris.push_back({a, b, d});
        m.tris.push_back({b, c, d});
      }
    }
  for (int i = 0; i <= nx; ++i) {
    m.node_sets["bottom"].push_back(i);
    m.node_sets["top"].push_back(ny * (nx + 1) + i);
  }
  for (int j = 0; j <= ny; ++j) {
    m.node_sets["left"].push_back(j * (nx + 1));
    m.node_sets["right"].push_back(j * (nx + 1) + nx);
  }
  return m;
}

inline Mesh grid_mesh(double width, double height, int nx, int ny, double distortion,
                      ElementKind kind) {
  return grid_mesh(width, height, nx, ny, distortion, kind == ElementKind::t3);
}

// One body of the given formulation in a model without gravity unless given.
inline Model<2> single_body_model(const Mesh& mesh, const Material& material, PlaneMode plane,
                               ElementKind kind, double thickness = 1.0,
                               double hourglass_coeff = 0.1,
                               const Vec2& gravity = Vec2::Zero()) {
  BodyInput<2> b;
  b.name = "body";
  b.mesh = mesh;
  b.material = material;
  b.thickness = thickness;
  b.quad_element =
      kind == ElementKind::q4_viscous || kind == ElementKind::q4_stiffness
          ? QuadElement::one_point_hourglass
          : QuadElement::full_2x2;
  b.hourglass.form =
      kind == ElementKind::q4_stiffness ? HourglassForm::stiffness : HourglassForm::viscous;
  b.hourglass.coeff = hourglass_coeff;
  return build_model({b}, plane, gravity);
}

}  // namespace ricochet::verification
