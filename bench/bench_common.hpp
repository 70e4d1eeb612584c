// Shared set-up of the benchmarks: a square plate of nx x nx cells in plane stress, built with
// one element formulation and one material, plus smooth, non-zero displacement and velocity
// fields with a small hourglass (checkerboard) component so every force term does real work.
#pragma once

#include <benchmark/benchmark.h>

#include <string>
#include <string_view>

#include "solver/model/model.hpp"

namespace ricochet::bench {

enum class ElementKind { q4_full_2x2, q4_one_point_viscous, q4_one_point_stiffness, t3 };
enum class MaterialKind { st_venant_kirchhoff, neo_hookean };

std::string_view element_name(ElementKind kind);
std::string_view material_name(MaterialKind kind);

// Plate side [m]; steel-like material (E = 200 GPa, nu = 0.3, rho = 7800 kg/m^3), thickness
// 0.01 m, default hourglass coefficient 0.1.
inline constexpr double plate_side = 0.1;

// The plate model with nx x nx cells (2 nx^2 triangles for ElementKind::t3). The last model
// built is cached, since the library calls a benchmark function several times per run.
const Model<2>& plate_model(ElementKind element, MaterialKind material, int nx);

// Per DOF (2n, interleaved): amplitude * (smooth mode of wavelength 2 * plate_side +
// 1e-3 * checkerboard hourglass mode), for the plate of nx x nx cells. Unit of `amplitude`
// is the unit of the field ([m] for displacement, [m/s] for velocity).
Eigen::VectorXd plate_field(const Model<2>& model, int nx, double amplitude);

// Marks the benchmark as failed (reported as an error) and makes ricochet_bench exit non-zero.
void fail(benchmark::State& state, const std::string& message);

// Number of fail() calls so far in this process.
int failure_count();

}  // namespace ricochet::bench
