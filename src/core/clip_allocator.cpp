#include <motormix/clip_allocator.hpp>

namespace motormix {

AllocationResult ClipAllocator::allocate(const AxisVector& demand, MotorVector& commands) const {
  mix_linear(demand, commands);
  return finish(demand, commands);
}

}  // namespace motormix
