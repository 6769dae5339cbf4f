#pragma once
// The one-dimensional problem `prioritized`'s repair solves for each axis
// that gives way: the largest share s in [0, 1] of a part (yaw, or roll and
// pitch) that still fits into the command range on top of a base, once all
// motors are shifted together along the thrust column by the best amount
// (rising by a cap at most: 0 when thrust may not rise, +inf when it may
// rise freely, between for limited airmode). At a motor count fixed at
// compile time, on local values.
//
// Motor i allows the shifts k (in thrust units, divided by thrust_i) in
//   L_i(s) = (lower - base_i - s part_i) / thrust_i <= k <= U_i(s) = (upper - ...) / thrust_i,
// so a shift exists iff the excess G(s) = max_i L_i(s) - min_j U_j(s) is
// <= 0, and also max_i L_i(s) <= cap when thrust may rise by cap at most. G is a maximum
// of lines minus a minimum of lines: convex and piecewise linear, so the
// scales that fit form an interval and the answer is its top.
//
// From s = 1 each step solves the piece of G in force exactly (its root).
// The tangent of a convex function lies below it, so no step passes the
// answer, and each step leaves one piece for good; G has fewer than 3n
// pieces, so the steps end within them. The cap only guards against
// rounding, and gives the scale up (-1, a safe answer) if ever reached.
// Motors that thrust does not move constrain s on their own, linearly.

#include <motormix/allocation/allocation.hpp>

#include "fixed_size.hpp"

#include <algorithm>
#include <limits>

namespace motormix::detail {

// An excess within rounding of a motor sitting on its limit counts as a fit.
inline constexpr double kFitTolerance = 1e-13;

// `x` with a rise's room added: x itself for no room (bit for bit, -0.0
// kept: the corners reproduce the named modes exactly).
inline double with_room(double x, double room) { return room == 0.0 ? x : x + room; }

// What one step needs of G at s: its value and the slope of the piece just
// below s.
struct ExcessAt {
  double excess;
  double slope;
};

// Steps down from s = top to the largest s >= bottom with excess <= 0
// (`excess_at(s)` gives G and its slope); -1 when there is none.
template <typename ExcessOf>
double top_of_fitting_scales(double bottom, double top, Eigen::Index motors,
                             const ExcessOf& excess_at) {
  double s = top;
  for (Eigen::Index step = 0; step < 4 * motors + 4; ++step) {
    const ExcessAt g = excess_at(s);
    if (g.excess <= kFitTolerance) return s;
    // Rising toward s = 0 (or flat): every smaller scale exceeds too.
    if (g.slope <= 0.0) return -1.0;
    s -= g.excess / g.slope;
    if (s < bottom) return -1.0;
  }
  return -1.0;
}

// The general case: any thrust column. `lift` is positive_inverse(thrust)
// (0 marks a motor the shift does not move); `all_lift` says there is none.
template <int N, typename Motors, typename Lift>
double largest_fitting_scale(const Motors& base, const Motors& part, const Lift& lift,
                             bool all_lift, Eigen::Index n, CommandRange range, double rise_cap) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  double bottom = 0.0;
  double top = 1.0;
  LocalMotors<N> low = (range.lower - base.array()).matrix().cwiseProduct(lift);  // L_i(0)
  LocalMotors<N> up = (range.upper - base.array()).matrix().cwiseProduct(lift);   // U_i(0)
  const LocalMotors<N> rate = part.cwiseProduct(lift);
  if (!all_lift) {
    for (Eigen::Index i = 0; i < count<N>(n); ++i) {
      if (lift[i] != 0.0) continue;
      // lower <= base_i + s part_i <= upper, and no say in the shift.
      const double room_up = range.upper - base[i];
      const double room_down = base[i] - range.lower;
      if (part[i] > 0.0) {
        top = std::min(top, room_up / part[i]);
        bottom = std::max(bottom, -room_down / part[i]);
      } else if (part[i] < 0.0) {
        top = std::min(top, -room_down / part[i]);
        bottom = std::max(bottom, room_up / part[i]);
      } else if (room_up < 0.0 || room_down < 0.0) {
        return -1.0;
      }
      low[i] = -kInf;
      up[i] = kInf;
    }
    if (bottom > top) return -1.0;
  }
  return top_of_fitting_scales(bottom, top, n, [&](double s) {
    // The motors that set the bounds at s and, among ties, the ones that
    // stay binding just below s (the slope of the piece to the left).
    double highest_low = -kInf;
    double lowest_up = kInf;
    double rate_low = -kInf;
    double rate_up = kInf;
    for (Eigen::Index i = 0; i < count<N>(n); ++i) {
      const double l = low[i] - s * rate[i];
      const double h = up[i] - s * rate[i];
      const bool sets_low = l > highest_low || (l == highest_low && rate[i] > rate_low);
      const bool sets_up = h < lowest_up || (h == lowest_up && rate[i] < rate_up);
      highest_low = sets_low ? l : highest_low;
      rate_low = sets_low ? rate[i] : rate_low;
      lowest_up = sets_up ? h : lowest_up;
      rate_up = sets_up ? rate[i] : rate_up;
    }
    ExcessAt g{highest_low - lowest_up, rate_up - rate_low};
    // The shift may rise by rise_cap at most: max L_i(s) - rise_cap <= 0.
    if (rise_cap < kInf) {
      const double over = highest_low - rise_cap;  // exact for a cap of 0
      if (over > g.excess) g = {over, -rate_low};
    }
    return g;
  });
}

// Equal lift and a base the same for every motor (thrust alone): G is
// linear in s, so the answer is closed form. `part` spans [low, high];
// `rise` is the rise cap in command units.
inline double largest_fitting_scale_uniform_base(double base, double part_low, double part_high,
                                                 CommandRange range, double rise) {
  double top = 1.0;
  const double spread = part_high - part_low;
  if (spread > 0.0) top = std::min(top, (range.upper - range.lower) / spread);
  if (rise < std::numeric_limits<double>::infinity()) {
    // The lowest motor must not need a shift up beyond the cap:
    // base + rise + s part_low >= lower.
    const double lifted = with_room(base, rise);
    if (lifted < range.lower - kFitTolerance) return -1.0;
    if (part_low < 0.0) top = std::min(top, (lifted - range.lower) / -part_low);
  }
  return top;
}

// The extremes of the base over each of two groups of motors.
struct GroupExtremes {
  double high_a, low_a, high_b, low_b;
};

// Equal lift, and a part that is `part_a` on one group of motors and
// `part_b` on the other (yaw on a multirotor whose rotors spin two ways):
// the spread of offset + base + s part is the largest of the spreads within
// each group (s drops out) and of the two cross terms, which are linear in
// s; the bottom, when thrust's rise is capped, is linear in s per group too. So
// the scales that fit are an intersection of half-lines: closed form.
inline double largest_fitting_scale_two_groups(double offset, const GroupExtremes& base,
                                               double part_a, double part_b, CommandRange range,
                                               double rise) {
  const double room = range.upper - range.lower;
  double lo = 0.0;
  double hi = 1.0;
  bool none = false;
  // a s <= c. The scales may narrow to a single point (a motor on each
  // limit), which rounding of the small coefficients can leave wider than
  // empty: the bounds from below allow the excess a step of
  // top_of_fitting_scales() allows, in command units.
  const auto keep = [&](double a, double c) {
    if (a > 0.0) {
      hi = std::min(hi, c / a);
    } else if (a < 0.0) {
      lo = std::max(lo, (c + kFitTolerance) / a);
    } else if (c < -kFitTolerance) {
      none = true;
    }
  };
  // Within a group every motor moves alike: only the base's spread counts.
  // An excess within rounding of a motor on its limit counts as a fit.
  if (base.high_a - base.low_a > room + kFitTolerance) return -1.0;
  if (base.high_b - base.low_b > room + kFitTolerance) return -1.0;
  keep(part_a - part_b, room - (base.high_a - base.low_b));  // a's top over b's bottom
  keep(part_b - part_a, room - (base.high_b - base.low_a));  // b's top over a's bottom
  if (rise < std::numeric_limits<double>::infinity()) {
    // offset + rise + low + s part >= lower for both groups' lowest motors.
    keep(-part_a, with_room(offset + base.low_a - range.lower, rise));
    keep(-part_b, with_room(offset + base.low_b - range.lower, rise));
  }
  return !none && lo <= hi ? hi : -1.0;
}

}  // namespace motormix::detail
