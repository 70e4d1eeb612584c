// The 3D force pass's kernels ranking the second Piola-Kirchhoff von Mises stress: one of the units
// the force pass is split over so that they compile in parallel (internal_forces_impl.hpp).
#include "solver/forces/element_kernels3.hpp"
#include "solver/forces/internal_forces_impl.hpp"

namespace ricochet {
RICOCHET_FORCE_PASS_VARIANTS(3, 1 + static_cast<int>(StressMeasure::pk2))
}  // namespace ricochet
