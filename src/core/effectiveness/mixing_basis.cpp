// MixingBasis apart from the per-cycle code of allocation.cpp: the healthy
// basis derives the effectiveness (a pseudo-inverse) and the axes from the
// matrix, and the kernel tests built for newer CPUs (test/CMakeLists.txt)
// compile allocation.cpp without that part of the core.
#include <motormix/allocation/allocation.hpp>

namespace motormix {

MixingBasis::MixingBasis(const MixingMatrix& m)
    : mixing(m), effectiveness(effectiveness_of(m)), controlled(controlled_axes(m)) {}

MixingBasis::MixingBasis(const MixingMatrix& m, const EffectivenessMatrix& e, AxisMask c)
    : mixing(m), effectiveness(e), controlled(c) {}

}  // namespace motormix
