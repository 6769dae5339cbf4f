#pragma once
// Strategy `prioritized`: sequential desaturation. Roll and pitch come
// first, then thrust, then yaw. Each step moves all motors along one axis's
// column by the gain that best removes the saturation the previous steps
// left, so a lower-priority axis gives way before a higher one.
//
// Airmode decides what may happen to thrust:
// - off: thrust may only be lowered to make room (at low throttle, roll and
//   pitch are reduced instead);
// - roll_pitch: thrust may also be raised so roll and pitch are kept at low
//   throttle; yaw is still mixed last and gives way first;
// - roll_pitch_yaw: as roll_pitch, with yaw mixed in from the start.
// Yaw may use `yaw_headroom` (fraction of the range) above the top before it
// is cut, and thrust is lowered afterwards to pay for it: at full thrust yaw
// keeps some authority instead of none.
//
// A demand whose linear mix already fits is returned as is. If the sequence
// above still leaves a motor out of range, a final repair keeps the promise
// of the priorities exactly: thrust moves first (only downward without
// airmode), then yaw is scaled down, and roll and pitch only when yaw alone
// cannot make room. Nothing is clipped that a lower priority could have paid
// for. The plain clip of the sequence's result (what PX4 does) is kept
// unless the repair delivers the demand better in that same priority order
// (it need not: scaling keeps the torque's direction, clipping does not), so
// the result is never worse than sequential desaturation with a clip.
//
// "Better" has a tie tolerance (`tie_tolerance`, normalized demand units,
// the same on each key of the order: roll/pitch, thrust, yaw). The repair
// replaces the clip only when it loses no key by more than the tolerance
// before a key it wins: a roll/pitch gain smaller than the tolerance never
// buys itself with thrust or yaw. 1e-3 (a thousandth of full roll) is below
// what a pilot or a rate loop can feel, and far below the thrust and yaw
// such a gain could cost. Where every key ties, the repair still needs to
// win one by more than kGainThatCounts (or the tolerance, if smaller): below
// that the two differ by rounding, not by priorities. A tolerance of 0 is
// the strict lexicographic order.

#include <motormix/allocation.hpp>
#include <motormix/allocation_settings.hpp>

#include <array>

namespace motormix {

class PrioritizedAllocator final : public MatrixAllocator {
 public:
  // The default tie tolerance, and the least gain that counts (see above).
  static constexpr double kDefaultTieTolerance = motormix::kDefaultTieTolerance;
  static constexpr double kGainThatCounts = 1e-5;

  PrioritizedAllocator(const MixingBasis& basis, CommandRange range, Airmode airmode,
                       double yaw_headroom, double tie_tolerance = kDefaultTieTolerance);
  std::string_view name() const override { return "prioritized"; }
  AllocationResult allocate(const AxisVector& demand, MotorVector& commands) const override;

  // Whether the undelivered demand `error_a` (as reported, axes the vehicle is
  // not commanded in already zero) is smaller than `error_b` in priority
  // order: roll/pitch (Euclidean), then thrust, then yaw; differences within
  // `tolerance` are ties, and ties go to `b`.
  static bool closer_in_priority_order(const AxisVector& error_a, const AxisVector& error_b,
                                       double tolerance = kDeliveredTolerance);

 private:
  // The per-cycle work at a motor count fixed at compile time (4, 6, 8, or
  // any other at dynamic size); defined in prioritized_allocator.cpp.
  template <int N>
  class Kernel;

  // The gains along one column that keep each motor in a range, as affine
  // functions of its command u_i: every gain in
  // [lowest_i - u_i inverse_i, highest_i - u_i inverse_i] does. A motor the
  // column barely moves (|entry| < float epsilon) gets (-inf, inf): it never
  // asks for a gain. Precomputed, so a desaturation step needs no division.
  struct InRangeGains {
    MotorVector inverse, lowest, highest;
  };
  static InRangeGains in_range_gains(const MotorVector& column, CommandRange range);

  Airmode airmode_;
  double yaw_headroom_;
  double tie_tolerance_;
  double gain_that_counts_;                   // min(tie_tolerance_, kGainThatCounts)
  std::array<InRangeGains, kNumAxes> gains_;  // per column, for the command range
  InRangeGains yaw_gains_with_headroom_;      // yaw, with yaw_headroom above the top
  MotorVector lift_inverse_;  // 1 / thrust where thrust > 0, else 0 (motors a shift moves)
  bool all_motors_lift_;      // no motor the thrust shift leaves in place
  bool equal_lift_;           // every motor the same share of thrust (symmetric multirotors)
  bool effectiveness_inverts_mixing_;  // E M = I on the controlled axes
  // The yaw column takes two values, one per spin direction (multirotors
  // with equal rotors): the repair's yaw scale is then closed form. The pads
  // are 0 on the motors of a group and +inf elsewhere (masked extremes).
  bool yaw_two_groups_ = false;
  double yaw_value_a_ = 0.0;
  double yaw_value_b_ = 0.0;
  MotorVector yaw_pad_a_, yaw_pad_b_;
};

}  // namespace motormix
