// Linearisation of the element forces for implicit schemes (docs/background.md, The implicit
// theta-scheme: each Newton iteration solves (M + theta xi dt^2 K_T + xi dt C) dv = ...). One
// element pass assembles the iteration matrix A = m_scale M + k_scale K_T + c_scale C into a sparse
// matrix of fixed pattern and, in the same pass, the internal forces exactly as internal_forces
// computes them.
// DOFs are interleaved (x0, y0, x1, ...) as everywhere in the solver.
#pragma once

#include <Eigen/SparseCore>
#include <vector>

#include "solver/elements/internal_forces.hpp"
#include "solver/model/model.hpp"

namespace ricochet {

// A sparse 2n x 2n symmetric matrix with the fixed pattern of the model's element couplings
// (full storage, both triangles), built once; assembly only overwrites values.
// Pattern: row 2a+i holds the columns 2b+k (k = 0, 1) of every node b that shares a cell with
// node a, and always its own two columns (so the diagonal exists even for a node in no cell).
struct SystemMatrix {
  Eigen::SparseMatrix<double, Eigen::RowMajor, int> matrix;
  // for each element of each block, in block order (q4_full, q4_hourglass, t3 as in Model), the
  // positions in matrix.valuePtr() of its (2N x 2N) entries, row-major over element dofs
  std::vector<int> slots;
  Eigen::VectorXd diagonal;  // copy of the diagonal after assembly (for Jacobi preconditioning)
  std::vector<int> diagonal_slots;  // position of entry (d, d) in matrix.valuePtr(), per DOF
};

SystemMatrix make_system_matrix(const Model& model);

// Assembles A = m_scale * M + k_scale * K_T(u) + c_scale * C into s.matrix (values overwritten),
// where M is the lumped mass (diagonal), K_T = d f_int / d u at velocity v (material + geometric
// stiffness of every element, plus the stiffness-form hourglass stiffness c gamma gamma^T),
// C = d f_int / d v (the viscous-form hourglass damping c gamma gamma^T, zero otherwise);
// in the same element pass writes f_int(u, v) into f_int (same values as internal_forces) and
// returns the same ForceTotals (energies only when with_energy).
// `s` must come from make_system_matrix(model). Performs no heap allocation.
ForceTotals assemble_system(const Model& model, const double* u, const double* v, double m_scale,
                            double k_scale, double c_scale, SystemMatrix& s, double* f_int,
                            bool with_energy);

}  // namespace ricochet
