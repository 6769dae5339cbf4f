#pragma once
// Strategy `prioritized`: sequential desaturation (roll and pitch first,
// then thrust, then yaw), airmode off / roll_pitch / roll_pitch_yaw, yaw
// headroom, and an exact repair that keeps the priorities where the
// sequence still leaves a motor out of range, never worse than the
// sequence's plain clip. What each step does and why, and what
// `tie_tolerance` means: docs/strategies.md, "prioritized, step by step".

#include <motormix/allocation/allocation.hpp>
#include <motormix/allocation/allocation_settings.hpp>

#include <array>
#include <cstdint>
#include <limits>

namespace motormix {

class PrioritizedAllocator final : public MatrixAllocator {
 public:
  // The default tie tolerance, and the least gain that counts (where every
  // key ties, the repair must win one by this much: below it the two differ
  // by rounding, not by priorities).
  static constexpr double kDefaultTieTolerance = motormix::kDefaultTieTolerance;
  static constexpr double kGainThatCounts = 1e-5;

  PrioritizedAllocator(const MixingBasis& basis, CommandRange range, AirmodeLimits airmode,
                       double yaw_headroom, double tie_tolerance = kDefaultTieTolerance);
  // A named mode: its corner of the limits.
  PrioritizedAllocator(const MixingBasis& basis, CommandRange range, Airmode airmode,
                       double yaw_headroom, double tie_tolerance = kDefaultTieTolerance)
      : PrioritizedAllocator(basis, range, limits_of(airmode), yaw_headroom, tie_tolerance) {}
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

  // The sequence flown: a named mode's own, or the limited one (any
  // limits off the corners; at a corner it would do the same steps).
  enum class Sequence : std::uint8_t { kOff, kRollPitch, kRollPitchYaw, kLimited };
  Sequence sequence_;
  // How far the thrust may rise (a gain along its column): for roll and
  // pitch, in the sequence and the repair (0 with airmode off, +inf with
  // it), and for yaw in the limited sequence.
  double rp_rise_cap_;
  double yaw_rise_cap_;
  // The same for roll and pitch in command units, where every motor has the
  // same share of thrust (the repair's closed forms).
  double rp_rise_command_;
  // The sequence leaves roll and pitch as demanded (it never scales them)
  // where their rise is not capped: roll_pitch, roll_pitch_yaw, and limits
  // whose roll/pitch share is 1.
  bool keeps_roll_pitch() const { return rp_rise_cap_ == std::numeric_limits<double>::infinity(); }
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
