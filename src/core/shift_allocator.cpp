#include <motormix/shift_allocator.hpp>

#include "fixed_size.hpp"
#include "report_kernel.hpp"

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
  inverse_direction_.resize(direction_.size());
  for (Eigen::Index i = 0; i < direction_.size(); ++i) {
    inverse_direction_[i] = direction_[i] > 0.0 ? 1.0 / direction_[i] : 0.0;
  }
}

namespace {

// feasible_shifts() at a fixed motor count, on local values; `inverse` is
// 1 / d where d > 0 and 0 elsewhere (no division per cycle).
template <int N, typename U, typename D>
ShiftInterval shifts_that_fit(const U& u, const D& inverse, Eigen::Index n, CommandRange range) {
  ShiftInterval k{-std::numeric_limits<double>::infinity(),
                  std::numeric_limits<double>::infinity()};
  bool stuck = false;
  for (Eigen::Index i = 0; i < detail::count<N>(n); ++i) {
    if (inverse[i] == 0.0) {
      stuck = stuck || u[i] < range.lower || u[i] > range.upper;
      continue;
    }
    k.lo = std::max(k.lo, (range.lower - u[i]) * inverse[i]);
    k.hi = std::min(k.hi, (range.upper - u[i]) * inverse[i]);
  }
  return stuck ? ShiftInterval{1.0, -1.0} : k;
}

}  // namespace

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
    ShiftInterval k = shifts_that_fit<N>(u, inverse, n, range);
    if (k.empty()) {
      // The spread alone does not fit: shrink the deviations from the mean
      // just enough, then shift.
      const double mean = u.mean();
      const double width = u.maxCoeff() - u.minCoeff();
      const double room = range.upper - range.lower;
      if (width > room) u = (u.array() - mean) * (room / width) + mean;
      k = shifts_that_fit<N>(u, inverse, n, range);
    }
    // The smallest shift that lands inside (0 when already inside).
    const double shift = k.empty() ? 0.0 : k.smallest();
    u = (u + shift * d).cwiseMax(range.lower).cwiseMin(range.upper);
    detail::MotorsView<N>(commands.data(), n) = u;
    return detail::describe_fixed<N>(effectiveness_, demand, u.data(), n, range, controlled_);
  });
}

}  // namespace motormix
