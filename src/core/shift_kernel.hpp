#pragma once
// The shifts along one direction (the thrust column, for the strategies that
// move all motors together) that keep every motor in range, at a motor count
// fixed at compile time. Shared by `shift` and `prioritized`'s repair.

#include <motormix/allocation.hpp>

#include "fixed_size.hpp"

#include <algorithm>
#include <limits>

namespace motormix::detail {

// 1 / d where d > 0 and 0 elsewhere: the per-cycle kernels multiply, they do
// not divide, and a zero marks a motor the shift cannot move.
inline MotorVector positive_inverse(const MotorVector& d) {
  MotorVector inverse(d.size());
  for (Eigen::Index i = 0; i < d.size(); ++i) inverse[i] = d[i] > 0.0 ? 1.0 / d[i] : 0.0;
  return inverse;
}

// A motor the shift cannot move counts as in range this close to it: it
// may have been put exactly on its limit, and the caller clamps afterwards.
inline constexpr double kUnmovedSlack = 1e-12;

// feasible_shifts() at N motors, on local values: the k for which u + k d is
// in range, given `inverse` = positive_inverse(d). A motor the shift cannot
// move that is out of range (by more than rounding) makes the interval empty.
// `all_move`: no zero in `inverse` (every motor moves), so the bounds are two
// packet reductions with no test per motor.
template <int N, typename U, typename D>
ShiftInterval shifts_that_fit(const U& u, const D& inverse, Eigen::Index n, CommandRange range,
                              bool all_move = false) {
  if (all_move) {
    return {((range.lower - u.array()) * inverse.array()).maxCoeff(),
            ((range.upper - u.array()) * inverse.array()).minCoeff()};
  }
  ShiftInterval k{-std::numeric_limits<double>::infinity(),
                  std::numeric_limits<double>::infinity()};
  bool stuck = false;
  for (Eigen::Index i = 0; i < detail::count<N>(n); ++i) {
    if (inverse[i] == 0.0) {
      stuck = stuck || u[i] < range.lower - kUnmovedSlack || u[i] > range.upper + kUnmovedSlack;
      continue;
    }
    k.lo = std::max(k.lo, (range.lower - u[i]) * inverse[i]);
    k.hi = std::min(k.hi, (range.upper - u[i]) * inverse[i]);
  }
  return stuck ? ShiftInterval{1.0, -1.0} : k;
}

}  // namespace motormix::detail
