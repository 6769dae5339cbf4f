#include <motormix/shift_allocator.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace motormix {

ShiftAllocator::ShiftAllocator(const MixingBasis& basis, CommandRange range)
    : MatrixAllocator(basis, range) {
  direction_ = mixing_.col(index(Axis::kThrust));
  const double peak = direction_.cwiseAbs().maxCoeff();
  // A motor with no share of thrust (a failed one) is not moved by the shift.
  if (peak > 0.0 && direction_.minCoeff() >= 0.0) {
    direction_ /= peak;
  } else {
    direction_.setOnes(mixing_.rows());
  }
}

AllocationResult ShiftAllocator::allocate(const AxisVector& demand, MotorVector& commands) const {
  mix_linear(demand, commands);
  ShiftInterval k = feasible_shifts(commands, direction_, range_);
  if (k.empty()) {
    // The spread alone does not fit: shrink the deviations from the mean just
    // enough, then shift. The width of the spread is the width of the
    // commands themselves, so no copy of them is needed.
    const double mean = commands.mean();
    const double width = commands.maxCoeff() - commands.minCoeff();
    const double room = range_.upper - range_.lower;
    if (width > room) commands = (commands.array() - mean) * (room / width) + mean;
    k = feasible_shifts(commands, direction_, range_);
  }
  // The smallest shift that lands inside (0 when already inside).
  const double shift = k.empty() ? 0.0 : k.smallest();
  commands += shift * direction_;
  return finish(demand, commands);
}

}  // namespace motormix
