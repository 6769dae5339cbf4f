#pragma once
// `prioritized` for a vehicle with motors out. Sequential desaturation on the
// reduced matrix keeps its rules, but scaling yaw toward zero is not always
// enough any more: with motors out, zero yaw itself can sit on the edge of
// what the working motors can do, so roll and pitch would be cut although a
// different yaw would leave room for them. When the reduced matrix does not
// deliver roll, pitch and thrust, this allocator mixes roll, pitch and thrust
// with yaw left free (their least-norm mix) and moves along the direction
// that changes yaw alone: if some yaw fits, roll, pitch and thrust are exact
// and yaw is as close to the demand as the range allows (a one-dimensional
// problem, solved in closed form). If no yaw fits, roll, pitch and thrust
// are desaturated in their priority order on that basis first. That
// one-dimensional search misses the commands that also move along the
// directions no axis sees (a hexa with one motor out has one): when it does
// not hold roll, pitch and thrust either, a bounded least-squares solve with
// yaw weighted far below the others searches all of them. It keeps whichever
// answer delivers the demand better in priority order: roll and pitch, then
// thrust, then yaw.

#include <motormix/allocation/allocation.hpp>
#include <motormix/allocation/optimal_allocator.hpp>
#include <motormix/allocation/prioritized_allocator.hpp>

#include <memory>

namespace motormix {

class YawYieldingAllocator final : public Allocator {
 public:
  // `reduced`: the failure's mixing basis; `yaw_free`: the same failure's
  // yaw-free mixing (FailureMixing::yaw_free).
  YawYieldingAllocator(const MixingBasis& reduced, const MixingMatrix& yaw_free, CommandRange range,
                       AirmodeLimits airmode, double yaw_headroom,
                       double tie_tolerance = PrioritizedAllocator::kDefaultTieTolerance);
  std::string_view name() const override { return "prioritized"; }
  int motors() const override { return full_.motors(); }
  AllocationResult allocate(const AxisVector& demand, MotorVector& commands) const override;

 private:
  // The gains g for which every motor of u + g * yaw_alone_ is in range.
  ShiftInterval room_along_yaw(const MotorVector& u) const;

  PrioritizedAllocator full_;
  PrioritizedAllocator yaw_free_;
  OptimalAllocator least_squares_;  // roll, pitch >> thrust >> yaw
  MotorVector yaw_alone_;           // command change per unit of yaw, nothing else
  MotorVector yaw_inverse_;         // its direction_inverse (0: a motor yaw does not move)
  EffectivenessMatrix effectiveness_;
  CommandRange range_;
  CycleConstants cycle_constants_;  // the range and the controlled axes, for the report
};

}  // namespace motormix
