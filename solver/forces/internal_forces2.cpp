// The force and stress passes of a Model<2>: internal_forces_impl.hpp's, with the 2D kernels.
#include "solver/forces/element_kernels2.hpp"
#include "solver/forces/internal_forces_impl.hpp"

namespace ricochet {
RICOCHET_FORCE_PASS_EXTERN(2)
RICOCHET_FORCE_PASSES(2)
}  // namespace ricochet
