// The oblique plate as the case file builds it, against the closed-form expectations of
// reference/oblique_plate_analytic.toml (geometry, mass, initial energy and momentum, wave
// speed). The meshes replace the circular arc by nx equal-width chords, so the mesh misses
// exactly one circular segment per chord, (R^2 / 2)(dphi - sin dphi) with phi = asin(x / R)
// (about L^3 / (12 R nx^2) in all: 1.1e-4 of the area on M1, 1.3e-5 on M2).
#include <gtest/gtest.h>

#include <toml++/toml.h>

#include <cmath>
#include <string>

#include "harness/input/case_setup.hpp"

namespace ricochet {
namespace {

const toml::table& analytic() {
  static const toml::table t = toml::parse_file(std::string(RICOCHET_SOURCE_DIR) + "/reference/oblique_plate_analytic.toml");
  return t;
}

double value(const char* table, const char* key) {
  const auto v = analytic()[table][key].value<double>();
  if (!v) throw std::runtime_error(std::string("reference missing ") + table + "." + key);
  return *v;
}

PreparedCase plate(const std::string& mesh) {
  return prepare_case(read_case(std::string(RICOCHET_SOURCE_DIR) + "/cases/oblique_plate.toml", {"mesh=" + mesh}));
}

// Exact area between the arc and its nx equal-width chords, relative to the plate area [-].
double chord_deficit(int nx) {
  const double L = 0.04, R = 0.101;
  double missing = 0.0;
  for (int i = 0; i < nx; ++i) {
    const double dphi = std::asin((-L / 2 + (i + 1) * L / nx) / R) - std::asin((-L / 2 + i * L / nx) / R);
    missing += 0.5 * R * R * (dphi - std::sin(dphi));
  }
  return missing / value("geometry", "area");
}

TEST(Reference, MassAndInitialStateMatchTheClosedForm) {
  for (const auto& [mesh, nx] : {std::pair{std::string("M1"), 12}, std::pair{std::string("M2"), 36}}) {
    const PreparedCase pc = plate(mesh);
    const double mass = 0.5 * pc.model<2>().mass.sum();  // x and y DOFs both carry the node mass
    const double rel = (value("body", "mass") - mass) / value("body", "mass");
    // The mesh loses exactly the chord deficit (1e-9: round-off of sums over ~3400 nodes).
    EXPECT_NEAR(rel, chord_deficit(nx), 1e-9) << mesh;

    Vec2 p = Vec2::Zero();
    double kinetic = 0.0;
    for (int i = 0; i < pc.model<2>().num_nodes(); ++i) {
      const Vec2 v = pc.model<2>().initial_velocity.segment<2>(2 * i);
      p += pc.model<2>().mass[2 * i] * v;
      kinetic += 0.5 * pc.model<2>().mass[2 * i] * v.squaredNorm();
    }
    const auto& m0 = *analytic()["body"]["momentum"].as_array();
    EXPECT_NEAR(p.x() / *m0[0].value<double>() - 1.0, -chord_deficit(nx), 1e-9) << mesh;
    EXPECT_NEAR(p.y() / *m0[1].value<double>() - 1.0, -chord_deficit(nx), 1e-9) << mesh;
    EXPECT_NEAR(kinetic / value("body", "kinetic_energy") - 1.0, -chord_deficit(nx), 1e-9) << mesh;
  }
}

TEST(Reference, WaveSpeedAndSagitta) {
  const PreparedCase pc = plate("M1");
  EXPECT_NEAR(material_wave_speed(pc.model<2>().bodies[0].material), value("waves", "plane_stress_dilatational"), 1e-12);
  // The lowest arc node is at the origin and the bottom corners at height s.
  double corner_y = 1.0;
  for (int i = 0; i < pc.model<2>().num_nodes(); ++i)
    if (std::abs(std::abs(pc.model<2>().ref(0, i)) - 0.02) < 1e-15) corner_y = std::min(corner_y, pc.model<2>().ref(1, i));
  EXPECT_NEAR(corner_y, value("geometry", "sagitta"), 1e-15);
}

}  // namespace
}  // namespace ricochet
