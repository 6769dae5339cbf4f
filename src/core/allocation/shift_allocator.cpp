#include <motormix/allocation/shift_allocator.hpp>

#include "fitting_scale.hpp"
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
  // A motor with no share of thrust (a failed one) is not moved by the
  // shift. A derived failure mixing leaves rounding (1e-15) where a share
  // is zero: that is zero too, not a reason to give up the thrust column.
  constexpr double kNoShare = 1e-12;
  if (peak > 0.0 && direction_.minCoeff() >= -kNoShare * peak) {
    direction_ /= peak;
    for (Eigen::Index i = 0; i < direction_.size(); ++i) {
      if (direction_[i] <= kNoShare) direction_[i] = 0.0;
    }
    base_per_thrust_ = peak;
  } else {
    direction_.setOnes(mixing_.rows());  // no thrust column to follow: all motors alike
    base_per_thrust_ = 0.0;
  }
  inverse_direction_ = detail::positive_inverse(direction_);
  every_motor_moves_ = (inverse_direction_.array() != 0.0).all();
  // After the scaling to a peak of 1, equal shares of thrust are all ones.
  constexpr double kAlike = 1e-12;
  all_motors_alike_ = (direction_.array() - 1.0).abs().maxCoeff() <= kAlike;
  // The one-pass path's report from its scalars (see allocate) holds when
  // the effectiveness undoes the mix on every controlled axis and the
  // thrust column itself is uniform (not only the direction made of ones).
  constexpr double kInverts = 1e-12;
  report_from_scalars_ = equal_thrust_shares() && effectiveness_inverts_mixing(kInverts);
  if (report_from_scalars_) thrust_per_shift_[index(Axis::kThrust)] = 1.0 / peak;
}

namespace {

// The smallest shift that lands inside (0 when already inside). When none
// does, the middle of the two bounds: the shift that leaves the smallest
// worst overshoot, which the clamp then takes off. That happens when the
// largest fitting scale leaves the interval a few ulps short of a point;
// shifting by nothing there could leave one end of the range unused and the
// other clipped hard.
double landing_shift(ShiftInterval k) { return k.empty() ? 0.5 * (k.lo + k.hi) : k.smallest(); }

}  // namespace

template <int N>
MOTORMIX_ALWAYS_INLINE AllocationResult ShiftAllocator::allocate_alike(const AxisVector& demand,
                                                                       double* out,
                                                                       Eigen::Index n) const {
  // Every motor moves by the shift itself: the lowest and highest command
  // give the shifts that fit and the spread, from one pass.
  // - The spread fits: the smallest shift into [lower - lowest, upper -
  //   highest] (ShiftInterval::smallest without its branches: 0 clamped
  //   into the interval, minsd and maxsd), added to the mix, which is kept
  //   to the last bit. No division.
  // - It does not: the spread is scaled by room / spread, and the only shift
  //   that then fits takes the lowest command to the lower limit (the highest
  //   lands on the upper one). Where the scale is centred makes no
  //   difference, so the commands are lower + (u - lowest) * factor, the
  //   division's result two operations from the end of the chain.
  // The branch follows the vehicle's state, not the demand's noise: a hover
  // fits cycle after cycle, a hard manoeuvre saturates for many cycles (and
  // of random demands in every axis, about 94 % miss on a quad X), so it is
  // predicted; a branchless form would put the division on every cycle.
  const double lower = range_.lower;
  const double upper = range_.upper;
  detail::LocalMotors<N> u(n);
  u.noalias() = detail::ConstMixingColumnsView<N>(mixing_by_column_.data(), n, kNumAxes) * demand;
  const double lowest = u.minCoeff();
  const double highest = u.maxCoeff();
  const double room = upper - lower;
  const double spread = highest - lowest;
  double factor = 1.0;
  double offset;
  if (spread <= room) {
    offset = std::max(lower - lowest, std::min(0.0, upper - highest));
    u.array() += offset;
  } else {
    factor = room / spread;
    offset = lower - lowest * factor;
    u = ((u.array() - lowest) * factor + lower).matrix();
  }
  detail::clamp_into_range<N>(u, cycle_constants_);
  detail::MotorsView<N>(out, n) = u;
  if (report_from_scalars_) {
    // With E M = I on the controlled axes and a thrust column of c
    // everywhere, E (factor M d + offset 1) = factor d + (offset / c) on
    // thrust: what is left undelivered follows from two scalars, with no
    // product by E. The clamp only takes off rounding here (the shift
    // fits, or misses by ulps), far below the delivered tolerance.
    const AxisVector left = (1.0 - factor) * demand - offset * thrust_per_shift_;
    return detail::describe_with<N>(detail::on_controlled_axes(left, cycle_constants_), u.data(), n,
                                    cycle_constants_);
  }
  return detail::describe_fixed<N>(effectiveness_, demand, u.data(), n, cycle_constants_);
}

template <int N>
#if defined(__GNUC__)
__attribute__((noinline))
#endif
AllocationResult
ShiftAllocator::allocate_along_thrust(const AxisVector& demand, double* out, Eigen::Index n) const {
  const CommandRange range = range_;
  const detail::ConstMotorsView<N> d(direction_.data(), n);
  const detail::ConstMotorsView<N> inverse(inverse_direction_.data(), n);
  detail::LocalMotors<N> u(n);
  u.noalias() = detail::ConstMixingColumnsView<N>(mixing_by_column_.data(), n, kNumAxes) * demand;
  ShiftInterval k = detail::shifts_that_fit<N>(u, inverse, n, range, every_motor_moves_);
  if (k.empty()) {
    // No shift fits: the torque part (all but thrust along the shift
    // direction) gives way, along its own direction, by the least amount
    // after which one does. That scale solves the same one-dimensional
    // problem as `prioritized`'s repair (fitting_scale.hpp), exactly.
    // Without a thrust column to follow, the base is the mean command.
    const double along =
        base_per_thrust_ > 0.0 ? base_per_thrust_ * demand[index(Axis::kThrust)] : u.mean();
    const detail::LocalMotors<N> base = d * along;
    const detail::LocalMotors<N> part = u - base;
    const double scale = detail::largest_fitting_scale<N>(
        base, part, inverse, every_motor_moves_, n, range, std::numeric_limits<double>::infinity());
    // None at all (a motor the shift cannot move is out of range on its
    // own): the torques go, and the clamp takes what is left.
    u = base + std::max(scale, 0.0) * part;
    k = detail::shifts_that_fit<N>(u, inverse, n, range, every_motor_moves_);
  }
  const double shift = landing_shift(k);
  u += shift * d;
  detail::clamp_into_range<N>(u, cycle_constants_);
  detail::MotorsView<N>(out, n) = u;
  return detail::describe_fixed<N>(effectiveness_, demand, u.data(), n, cycle_constants_);
}

AllocationResult ShiftAllocator::allocate(const AxisVector& demand, MotorVector& commands) const {
  const Eigen::Index motors = mixing_.rows();
  commands.resize(motors);
  return detail::with_motor_count<detail::FixedCounts::kUpTo16>(
      motors,
      [](auto size, const ShiftAllocator& self, const AxisVector& target, double* out,
         Eigen::Index n) MOTORMIX_INLINE_LAMBDA {
        constexpr int N = decltype(size)::value;
        return self.all_motors_alike_ ? self.allocate_alike<N>(target, out, n)
                                      : self.allocate_along_thrust<N>(target, out, n);
      },
      *this, demand, commands.data(), motors);
}

}  // namespace motormix
