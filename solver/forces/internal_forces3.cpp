// The force and stress passes of a Model<3>: internal_forces_impl.hpp's, with the 3D kernels.
#include "solver/forces/element_kernels3.hpp"
#include "solver/forces/internal_forces_impl.hpp"

namespace ricochet {
RICOCHET_FORCE_PASS_EXTERN(3)
RICOCHET_FORCE_PASSES(3)
}  // namespace ricochet
