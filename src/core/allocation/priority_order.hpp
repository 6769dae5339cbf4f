#pragma once
// `prioritized`'s order of the undelivered demand (roll/pitch, then thrust,
// then yaw, with tolerances) and the decision between the sequence's clip
// and the repair that follows from it. Internal to the core; the kernel in
// prioritized_allocator.cpp inlines them.

#include <motormix/allocation/allocation.hpp>

#include "fixed_size.hpp"

#include <cmath>

namespace motormix::detail {

// The roll/pitch part of an error, squared...
inline double roll_pitch_square(const AxisVector& e) {
  return e[index(Axis::kRoll)] * e[index(Axis::kRoll)] +
         e[index(Axis::kPitch)] * e[index(Axis::kPitch)];
}
// ...and Euclidean. Errors are at most a few units: a plain root is exact
// enough and much cheaper than hypot's overflow guards.
inline double roll_pitch_norm(const AxisVector& e) { return std::sqrt(roll_pitch_square(e)); }

// Which of the clip and the repair wins on roll and pitch, from the clip's
// squared error and the repair's error as its scales predict it, where the
// prediction alone decides it (prefer_repair below): the clip when it is
// closer by more than the gain that counts, the repair when it is closer by
// more than the tie tolerance. Both margins carry twice the delivered
// tolerance, so that the prediction's rounding (E M = I within 1e-9) cannot
// turn them. Squares compare as their roots do, so no root waits on the way.
enum class RollPitchVerdict { kUndecided, kClipCloser, kRepairCloser };
inline RollPitchVerdict roll_pitch_verdict(double clip_square, double repair_error, double counts,
                                           double tie) {
  constexpr double kMargin = 2.0 * kDeliveredTolerance;
  const double below = repair_error - counts - kMargin;
  if (below > 0.0 && clip_square < below * below) return RollPitchVerdict::kClipCloser;
  const double above = repair_error + tie + kMargin;
  if (clip_square > above * above) return RollPitchVerdict::kRepairCloser;
  return RollPitchVerdict::kUndecided;
}

// closer_in_priority_order() itself, inlined into the kernel (a call on
// most saturating demands): the first key that differs by more than the
// tolerance decides.
MOTORMIX_ALWAYS_INLINE bool closer_in_order(const AxisVector& a, const AxisVector& b,
                                            double tolerance) {
  const double rp_a = roll_pitch_norm(a);
  const double rp_b = roll_pitch_norm(b);
  if (rp_a < rp_b - tolerance) return true;
  if (rp_a > rp_b + tolerance) return false;
  const double thrust_a = std::abs(a[index(Axis::kThrust)]);
  const double thrust_b = std::abs(b[index(Axis::kThrust)]);
  if (thrust_a < thrust_b - tolerance) return true;
  if (thrust_a > thrust_b + tolerance) return false;
  return std::abs(a[index(Axis::kYaw)]) < std::abs(b[index(Axis::kYaw)]) - tolerance;
}

// Whether the repair replaces the clip (the sequence's result clipped, what
// PX4 delivers): only when it is no worse in priority order with ties within
// `tie`, and better with ties within `counts` only. A higher priority
// within `tie` of the clip's does not buy itself a hair more at the cost of
// a lower one; where every key ties, a gain larger than `counts` still wins.
MOTORMIX_ALWAYS_INLINE bool prefer_repair(const AxisVector& repair, const AxisVector& clip,
                                          double counts, double tie) {
  return !closer_in_order(clip, repair, tie) && closer_in_order(repair, clip, counts);
}

}  // namespace motormix::detail
