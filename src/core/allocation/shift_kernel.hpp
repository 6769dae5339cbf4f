#pragma once
// The shifts along one direction (the thrust column, for the strategies that
// move all motors together) that keep every motor in range, at a motor count
// fixed at compile time. Shared by `shift` and `prioritized`'s repair.

#include <motormix/allocation/allocation.hpp>

#include "fixed_size.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace motormix::detail {

// 1 / d for the entries that move a motor, 0 for the ones that do not: the
// per-cycle kernels multiply, they do not divide, and a zero marks a motor
// the direction cannot move. `positive_only`: only d > 0 moves (a thrust
// shift); otherwise |d| >= `negligible` of either sign does (a torque).
template <typename Out>
void direction_inverse(const MotorVector& d, bool positive_only, double negligible, Out& out) {
  for (Eigen::Index i = 0; i < d.size(); ++i) {
    const bool moves = positive_only ? d[i] > 0.0 : std::abs(d[i]) >= negligible;
    out[i] = moves ? 1.0 / d[i] : 0.0;
  }
}
inline MotorVector positive_inverse(const MotorVector& d) {
  MotorVector inverse(d.size());
  direction_inverse(d, true, 0.0, inverse);
  return inverse;
}

// A motor the shift cannot move counts as in range this close to it: it
// may have been put exactly on its limit, and the caller clamps afterwards.
inline constexpr double kUnmovedSlack = 1e-12;

// The gains k for which every motor of u + k d is in range, at N motors, on
// local values, given `inverse` from direction_inverse(d). The one place
// this is computed: the public feasible_shifts(), the shift and repair
// steps, and the yaw room of a vehicle with motors out all call it. A motor
// the direction cannot move that is out of range (by more than rounding)
// makes the interval empty. `positive`: every moving entry is positive
// (a thrust column), so each motor's lower bound comes from the bottom of
// the range and the min/max per motor is skipped. `all_move`: no zero in
// `inverse`, so the bounds are two packet reductions with no test per motor.
template <int N, typename U, typename D>
ShiftInterval shifts_that_fit(const U& u, const D& inverse, Eigen::Index n, CommandRange range,
                              bool all_move = false, bool positive = true) {
  if (all_move && positive) {
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
    const double to_lower = (range.lower - u[i]) * inverse[i];
    const double to_upper = (range.upper - u[i]) * inverse[i];
    k.lo = std::max(k.lo, std::min(to_lower, to_upper));
    k.hi = std::min(k.hi, std::max(to_lower, to_upper));
  }
  return stuck ? ShiftInterval{1.0, -1.0} : k;
}

}  // namespace motormix::detail
