// Linearisation of the element forces for implicit schemes (docs/background.md, The implicit
// theta-scheme: each Newton iteration solves (M + theta xi dt^2 K_T + xi dt C) dv = ...). One
// element pass assembles the iteration matrix A = m_scale M + k_scale K_T + c_scale C into a sparse
// matrix of fixed pattern and, in the same pass, the internal forces exactly as internal_forces
// computes them.
// DOFs are interleaved (x0, y0, x1, ...) as everywhere in the solver; in 3D (x0, y0, z0, x1, ...).
#pragma once

#include <Eigen/SparseCore>
#include <vector>

#include "solver/forces/internal_forces.hpp"
#include "solver/model/model.hpp"

namespace ricochet {

// A sparse Dn x Dn symmetric matrix (D = 2 or 3 DOFs per node) with the fixed pattern of the
// model's element couplings (full storage, both triangles), built once by the same code for
// either D (system_pattern.hpp); assembly only overwrites values. Pattern: row Da+i holds the
// columns Db+k (k < D) of every node b that shares a cell with node a, and always its own D
// columns (so the diagonal exists even for a node in no cell).
struct SystemMatrix {
  Eigen::SparseMatrix<double, Eigen::RowMajor, int> matrix;
  // for each element of each block, in the order every pass visits the blocks (ModelBlocks<D>::kKinds:
  // q4_hourglass, q4_full, t3; in 3D hex8_hourglass, hex8_full, tet4), the positions in
  // matrix.valuePtr() of its (DN x DN) entries, row-major over element dofs
  std::vector<int> slots;
  Eigen::VectorXd diagonal;  // copy of the diagonal after assembly (for Jacobi preconditioning)
  std::vector<int> diagonal_slots;  // position of entry (d, d) in matrix.valuePtr(), per DOF
};

// The matrix's pattern for a model (system_pattern.hpp), for D = 2 and 3.
template <int D>
SystemMatrix make_system_matrix(const Model<D>& model);

// Assembles A = m_scale * M + k_scale * K_T(u) + c_scale * C into s.matrix (values overwritten),
// where M is the lumped mass (diagonal), K_T = d f_int / d u at velocity v (material + geometric
// stiffness of every element, plus the stiffness-form hourglass stiffness c gamma gamma^T),
// C = d f_int / d v (the viscous-form hourglass damping c gamma gamma^T, zero otherwise);
// writes f_int(u, v) into f_int (same values as internal_forces) and returns the same
// ForceTotals (energies only when with_energy). The frame is one (assemble_with,
// system_pattern.hpp); the element matrices are the dimension's: in 2D (tangent.cpp) from the
// element kernels, in the same pass as the forces; in 3D (tangent3.cpp) those of element3d.hpp
// (hex8_stiffness, hex8_one_point_stiffness, tet4_stiffness) on the geometry rebuilt by
// cell_geometry(), with f_int and the totals from the 3D force pass, so the Newton residual and
// the assembly see the same forces bit for bit.
// `s` must come from make_system_matrix(model). Performs no heap allocation.
template <int D>
ForceTotals assemble_system(const Model<D>& model, const double* u, const double* v, double m_scale,
                            double k_scale, double c_scale, SystemMatrix& s, double* f_int,
                            bool with_energy);
template <>
ForceTotals assemble_system(const Model<2>& model, const double* u, const double* v, double m_scale,
                            double k_scale, double c_scale, SystemMatrix& s, double* f_int, bool with_energy);
template <>
ForceTotals assemble_system(const Model<3>& model, const double* u, const double* v, double m_scale,
                            double k_scale, double c_scale, SystemMatrix& s, double* f_int, bool with_energy);

}  // namespace ricochet
