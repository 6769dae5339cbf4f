#include <motormix/clip_allocator.hpp>

namespace motormix {

AllocationResult ClipAllocator::allocate(const AxisVector& demand, MotorVector& commands) const {
  return mix_and_clip(demand, commands);
}

}  // namespace motormix
