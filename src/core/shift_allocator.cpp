#include <motormix/shift_allocator.hpp>

#include "fixed_size.hpp"
#include "report_kernel.hpp"
#include "shift_kernel.hpp"

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
  inverse_direction_ = detail::positive_inverse(direction_);
}

AllocationResult ShiftAllocator::allocate(const AxisVector& demand, MotorVector& commands) const {
  const Eigen::Index n = mixing_.rows();
  commands.resize(n);
  const CommandRange range = range_;
  return detail::with_motor_count(n, [&](auto size) {
    constexpr int N = decltype(size)::value;
    const detail::ConstMotorsView<N> d(direction_.data(), n);
    const detail::ConstMotorsView<N> inverse(inverse_direction_.data(), n);
    detail::LocalMotors<N> u(n);
    u.noalias() = detail::ConstMixingView<N>(mixing_.data(), n, kNumAxes) * demand;
    ShiftInterval k = detail::shifts_that_fit<N>(u, inverse, n, range);
    if (k.empty()) {
      // The spread alone does not fit: shrink the deviations from the mean
      // just enough, then shift.
      const double mean = u.mean();
      const double width = u.maxCoeff() - u.minCoeff();
      const double room = range.upper - range.lower;
      if (width > room) u = (u.array() - mean) * (room / width) + mean;
      k = detail::shifts_that_fit<N>(u, inverse, n, range);
    }
    // The smallest shift that lands inside (0 when already inside).
    const double shift = k.empty() ? 0.0 : k.smallest();
    u = (u + shift * d).cwiseMax(range.lower).cwiseMin(range.upper);
    detail::MotorsView<N>(commands.data(), n) = u;
    return detail::describe_fixed<N>(effectiveness_, demand, u.data(), n, range, controlled_);
  });
}

}  // namespace motormix
