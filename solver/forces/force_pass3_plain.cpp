// The 3D force pass's kernels without stresses (the explicit and implicit schemes' passes between
// samples): one of the units the force pass is split over so that they compile in parallel
// (internal_forces_impl.hpp).
#include "solver/forces/element_kernels3.hpp"
#include "solver/forces/internal_forces_impl.hpp"

namespace ricochet {
RICOCHET_FORCE_PASS_PLAIN(3)
}  // namespace ricochet
