// Basic fixed-size types shared by the solver core.
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>  // determinant() and inverse() of fixed-size matrices

namespace ricochet {

using Vec2 = Eigen::Vector2d;
using Mat2 = Eigen::Matrix2d;
// Three dimensions (docs/architecture.md): the 3D laws, kernels and contact use these.
using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

// In-plane assumption of a 2D model. Plane stress uses each body's thickness; plane strain
// uses it too (a slab of that depth), so energies and forces are per body, never per metre.
enum class PlaneMode { stress, strain };

// Cells per batch of the vectorized force kernels (element_kernels2.hpp): one AVX-512 register
// of doubles, two AVX2 registers.
inline constexpr int kLanes = 8;

}  // namespace ricochet
