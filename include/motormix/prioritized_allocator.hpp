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
// instead when it delivers the demand better in that same priority order
// (it can: scaling keeps the torque's direction, clipping need not), so the
// result is never worse than sequential desaturation with a clip.

#include <motormix/allocation.hpp>

namespace motormix {

enum class Airmode : std::uint8_t { kOff, kRollPitch, kRollPitchYaw };

class PrioritizedAllocator final : public MatrixAllocator {
 public:
  PrioritizedAllocator(const MixingBasis& basis, CommandRange range, Airmode airmode,
                       double yaw_headroom);
  std::string_view name() const override { return "prioritized"; }
  AllocationResult allocate(const AxisVector& demand, MotorVector& commands) const override;

  // Whether the undelivered demand `error_a` (as reported, axes the vehicle is
  // not commanded in already zero) is smaller than `error_b` in priority
  // order: roll/pitch (Euclidean), then thrust, then yaw; differences within
  // `tolerance` are ties, and ties go to `b`.
  static bool closer_in_priority_order(const AxisVector& error_a, const AxisVector& error_b,
                                       double tolerance = kDeliveredTolerance);

 private:
  enum class Direction { kBoth, kDecreaseOnly };
  // Gain along `v` that removes as much of the range violation as possible.
  double desaturation_gain(const MotorVector& u, const MotorVector& v, CommandRange range) const;
  // Moves u along the column of `axis`, and the effective demand with it.
  void desaturate(MotorVector& u, AxisVector& effective, Axis axis, CommandRange range,
                  Direction direction = Direction::kBoth) const;
  void mix_yaw(double yaw, MotorVector& u, AxisVector& effective) const;
  void repair(AxisVector& effective, MotorVector& u) const;
  // Largest s in [0, 1] for which base + s * part can be shifted along the
  // thrust column into range (only downward unless may_raise); -1 when not
  // even s = 0 fits. Closed form: each repair step is one-dimensional.
  double largest_fitting_scale(const MotorVector& base, const MotorVector& part,
                               bool may_raise) const;
  const MotorVector& column(Axis axis) const;

  Airmode airmode_;
  double yaw_headroom_;
  MotorVector roll_, pitch_, yaw_, thrust_;  // columns of the mixing matrix
};

}  // namespace motormix
