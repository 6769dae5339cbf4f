#pragma once
// Strategy `shift`: keep the differences between motors, move them together.
//
// When the linear mix leaves the range, every motor is shifted along the
// thrust column (all motors alike for identical rotors) by just enough to
// bring them back: the torques (or, for wheels, the turn) are kept and
// thrust (forward speed) gives way. If no shift brings every motor into
// range (the spread between motors is too wide), the torque part is scaled
// down along its own direction by the least amount after which one does,
// and the report says which axes lost.

#include <motormix/allocation/allocation.hpp>

namespace motormix {

class ShiftAllocator final : public MatrixAllocator {
 public:
  ShiftAllocator(const MixingBasis& basis, CommandRange range);
  std::string_view name() const override { return "shift"; }
  AllocationResult allocate(const AxisVector& demand, MotorVector& commands) const override;

 private:
  // The two paths of allocate() at N motors (N == Eigen::Dynamic: a count
  // without its own instantiation, see src/core/allocation/fixed_size.hpp). All
  // motors alike: one pass, inlined. Along a thrust column that is not
  // uniform: out of line, so that the one-pass path keeps no stack frame
  // for it.
  template <int N>
  AllocationResult allocate_alike(const AxisVector& demand, double* out, Eigen::Index n) const;
  template <int N>
  AllocationResult allocate_along_thrust(const AxisVector& demand, double* out,
                                         Eigen::Index n) const;

  MotorVector direction_;  // shift direction: the thrust column scaled to max 1 (or all ones)
  MotorVector inverse_direction_;     // 1 / direction where it is positive, else 0
  bool every_motor_moves_ = true;     // no zero in inverse_direction_
  bool all_motors_alike_ = false;     // direction all ones: the shift moves every motor alike
  bool report_from_scalars_ = false;  // alike, E M = I on the controlled axes: see allocate
  // The thrust a shift of 1 delivers, as an axis vector (0, 0, 0, 1 / each
  // motor's equal share): zero unless report_from_scalars_.
  AxisVector thrust_per_shift_ = AxisVector::Zero();
  double base_per_thrust_ = 0.0;  // thrust column = direction * this (0: no column to follow)
};

}  // namespace motormix
