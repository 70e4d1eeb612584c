// The implicit scheme's linear algebra on the oblique plate's iteration matrix
// A = M + theta xi dt^2 K_T (theta = xi = 1/2, u = 0, the pattern and values of a run's first
// Newton iteration), per mesh and step: numeric factorization (symbolic analysis done once,
// outside the timing) and one solve, for CHOLMOD's two methods and Eigen's SimplicialLDLT (the
// hand-written sparse LDL^T that CHOLMOD replaced measured like the latter; docs/implicit.md),
// and one Jacobi-PCG solve to 1e-12 for comparison; on M2 and M2x2 also with the METIS and
// CHOLMOD nested-dissection orderings (names ending _metis, _nesdis; AMD has none). Times per
// call, with CHOLMOD's flop count and L's entries; run with --benchmark_repetitions.
#include <benchmark/benchmark.h>

#include <Eigen/SparseCholesky>
#include <memory>
#include <string>
#include <vector>

#include "bench_common.hpp"
#include "harness/input/case_setup.hpp"
#include "solver/forces/tangent.hpp"
#include "solver/linear/cholmod_factor.hpp"
#include "solver/linear/pcg.hpp"

namespace ricochet::bench {
namespace {

struct Matrix {
  SystemMatrix system;
  Eigen::VectorXd b;
};

// The iteration matrix of cases/oblique_plate.toml on `mesh` at step `dt` (built once per cell).
const Matrix& iteration_matrix(const std::string& mesh, const std::string& dt) {
  static std::string key;
  static std::unique_ptr<Matrix> cached;
  if (cached && key == mesh + dt) return *cached;
  const CaseSpec spec = read_case(std::string(RICOCHET_SOURCE_DIR) + "/cases/oblique_plate.toml",
                                  {"mesh=" + mesh, "time.dt=" + dt});
  const PreparedCase pc = prepare_case(spec);
  const Model<2>& model = pc.model<2>();
  const double h = pc.settings.dt;
  cached = std::make_unique<Matrix>();
  cached->system = make_system_matrix(model);
  const int n = model.num_dofs();
  Eigen::VectorXd u = Eigen::VectorXd::Zero(n), v = model.initial_velocity, f(n);
  assemble_system(model, u.data(), v.data(), 1.0, 0.25 * h * h, 0.5 * h, cached->system, f.data(), false);
  cached->b = -h * f + model.mass;  // any smooth right-hand side with the scale of G
  key = mesh + dt;
  return *cached;
}

enum class Solver { cholmod_supernodal, cholmod_simplicial, eigen_simplicial_ldlt };
using Ordering = CholmodFactor::Ordering;

void factorize(benchmark::State& state, Solver solver, Ordering ordering, const std::string& mesh,
               const std::string& dt) {
  const Matrix& m = iteration_matrix(mesh, dt);
  const auto& a = m.system.matrix;
  Eigen::VectorXd x(a.rows());
  bool ok = true;
  if (solver == Solver::cholmod_supernodal || solver == Solver::cholmod_simplicial) {
    CholmodFactor f;
    f.analyze(a,
              solver == Solver::cholmod_supernodal ? CholmodFactor::Method::supernodal
                                                   : CholmodFactor::Method::simplicial,
              ordering);
    for (auto _ : state) ok = ok && f.factorize(a.valuePtr());
    state.counters["factor_nonzeros"] = f.factor_nonzeros();
    state.counters["factor_flops"] = f.factor_flops();
  } else {
    const Eigen::SparseMatrix<double> col = a;
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> f;
    f.analyzePattern(col);
    for (auto _ : state) {
      f.factorize(col);
      ok = ok && f.info() == Eigen::Success;
    }
  }
  if (!ok) fail(state, "factorization failed");
  state.counters["n"] = static_cast<double>(a.rows());
}

void solve(benchmark::State& state, Solver solver, Ordering ordering, const std::string& mesh,
           const std::string& dt, bool single) {
  const Matrix& m = iteration_matrix(mesh, dt);
  const auto& a = m.system.matrix;
  Eigen::VectorXd x(a.rows());
  CholmodFactor f;
  f.analyze(a,
            solver == Solver::cholmod_supernodal ? CholmodFactor::Method::supernodal
                                                 : CholmodFactor::Method::simplicial,
            ordering);
  if (!f.factorize(a.valuePtr())) fail(state, "factorization failed");
  Eigen::VectorXd exact(a.rows());
  f.solve(m.b, exact);
  f.use_single(single);
  for (auto _ : state) {
    f.solve(m.b, x);
    benchmark::DoNotOptimize(x.data());
  }
  // How far the single-precision copy's solution is from the double factor's (0 for double).
  state.counters["relative_difference"] = (x - exact).norm() / exact.norm();
  state.counters["solve_bytes"] = f.solve_bytes();
}

void pcg_solve(benchmark::State& state, const std::string& mesh, const std::string& dt) {
  const Matrix& m = iteration_matrix(mesh, dt);
  const auto& a = m.system.matrix;
  Pcg pcg;
  pcg.resize(static_cast<int>(a.rows()));
  const Eigen::VectorXd inv_diag = m.system.diagonal.cwiseInverse();
  Eigen::VectorXd x(a.rows());
  int iterations = 0;
  for (auto _ : state) {
    x.setZero();
    const PcgResult r = pcg.solve(a, inv_diag, m.b, x, 1e-12, 100000);
    if (!r.converged) fail(state, "PCG did not converge");
    iterations = r.iterations;
  }
  state.counters["cg_iterations"] = iterations;
}

const char* name(Solver s) {
  switch (s) {
    case Solver::cholmod_supernodal: return "cholmod_supernodal";
    case Solver::cholmod_simplicial: return "cholmod_simplicial";
    case Solver::eigen_simplicial_ldlt: return "eigen_simplicial_ldlt";
  }
  return "";
}

// The AMD ordering keeps the names the benchmark had before orderings were compared
// (cholmod_simplicial); the others add theirs (cholmod_simplicial_metis).
std::string name(Solver s, Ordering o) {
  const std::string base = name(s);
  if (s == Solver::eigen_simplicial_ldlt || o == Ordering::amd) return base;
  return base + (o == Ordering::metis ? "_metis" : "_nesdis");
}

void register_all() {
  for (const char* mesh : {"M1", "M2", "M2x2", "M2x4"})
    for (const char* dt : {"1e-4", "1e-6"}) {
      const std::string cell = std::string(mesh) + "/dt" + dt;
      // The orderings compared on M2 and M2x2 (docs/implicit.md); AMD alone elsewhere.
      const bool orderings = std::string(mesh) == "M2" || std::string(mesh) == "M2x2";
      for (Solver s : {Solver::cholmod_supernodal, Solver::cholmod_simplicial, Solver::eigen_simplicial_ldlt})
        for (Ordering o : {Ordering::amd, Ordering::metis, Ordering::nesdis}) {
          if ((s == Solver::eigen_simplicial_ldlt || !orderings) && o != Ordering::amd) continue;
          benchmark::RegisterBenchmark(("linear_factorize/" + name(s, o) + "/" + cell).c_str(),
                                       [=](benchmark::State& st) { factorize(st, s, o, mesh, dt); })
              ->Unit(benchmark::kMillisecond);
        }
      for (Solver s : {Solver::cholmod_supernodal, Solver::cholmod_simplicial})
        for (Ordering o : {Ordering::amd, Ordering::metis, Ordering::nesdis})
          for (bool single : {false, true})
            if ((orderings || o == Ordering::amd) && (!single || o == Ordering::amd))
              benchmark::RegisterBenchmark(
                  ("linear_solve/" + name(s, o) + (single ? "_single" : "") + "/" + cell).c_str(),
                  [=](benchmark::State& st) { solve(st, s, o, mesh, dt, single); })
                  ->Unit(benchmark::kMicrosecond);
      benchmark::RegisterBenchmark(("linear_solve/pcg/" + cell).c_str(),
                                   [=](benchmark::State& st) { pcg_solve(st, mesh, dt); })
          ->Unit(benchmark::kMicrosecond);
    }
}

const int registered = (register_all(), 0);

}  // namespace
}  // namespace ricochet::bench
