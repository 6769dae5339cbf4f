#include <motormix/allocation/yaw_yielding_allocator.hpp>

#include "shift_kernel.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace motormix {

namespace {
// Below this (normalized units) an axis counts as delivered.
constexpr double kHeld = kDeliveredTolerance;

// Weights of the least-squares fallback: squared, roll and pitch count 11
// times thrust, and thrust 900 times yaw: close to a strict priority order
// (on the hexa flight with a motor out, roll within 1e-3 and thrust within
// 6e-3 of the demand while yaw gives way) with a well-conditioned solve.
const OptimalSettings kPriorityWeights{AxisVector(1.0, 1.0, 0.01, 0.3), 100};

// Between candidates, errors this close count as equal (a tenth of a
// percent of full authority): the least-squares answer holds roll and pitch
// to about 1e-4 where it trades with yaw, which must not lose to an answer
// that is exact in roll and pitch but drops a lot of thrust.
constexpr double kCandidateTie = 1e-3;

bool holds_roll_pitch_thrust(const AxisVector& unallocated) {
  return std::abs(unallocated[index(Axis::kRoll)]) <= kHeld &&
         std::abs(unallocated[index(Axis::kPitch)]) <= kHeld &&
         std::abs(unallocated[index(Axis::kThrust)]) <= kHeld;
}
}  // namespace

YawYieldingAllocator::YawYieldingAllocator(const MixingBasis& reduced, const MixingMatrix& yaw_free,
                                           CommandRange range, AirmodeLimits airmode,
                                           double yaw_headroom, double tie_tolerance)
    : full_(reduced, range, airmode, yaw_headroom, tie_tolerance),
      yaw_free_(MixingBasis(yaw_free, reduced.effectiveness, reduced.controlled), range, airmode,
                yaw_headroom, tie_tolerance),
      least_squares_(reduced, range, kPriorityWeights),
      yaw_alone_(yaw_free.col(index(Axis::kYaw))),
      yaw_inverse_(yaw_alone_.size()),
      effectiveness_(reduced.effectiveness),
      range_(range),
      cycle_constants_(range, reduced.controlled) {
  // Entries this small do not move a motor: the yaw-free mix leaves them.
  detail::direction_inverse(yaw_alone_, /*positive_only=*/false,
                            std::numeric_limits<double>::epsilon(), yaw_inverse_);
}

ShiftInterval YawYieldingAllocator::room_along_yaw(const MotorVector& u) const {
  return detail::shifts_that_fit<Eigen::Dynamic>(u, yaw_inverse_, u.size(), range_,
                                                 /*all_move=*/false, /*positive=*/false);
}

AllocationResult YawYieldingAllocator::allocate(const AxisVector& demand,
                                                MotorVector& commands) const {
  const AllocationResult full = full_.allocate(demand, commands);
  if (holds_roll_pitch_thrust(full.unallocated)) return full;

  AxisVector without_yaw = demand;
  without_yaw[index(Axis::kYaw)] = 0.0;
  // Roll, pitch and thrust exactly, in their least-norm mix, and yaw as
  // the range allows along the direction that changes nothing else: when
  // some amount of yaw fits, that is the answer.
  MotorVector free_commands;
  free_commands.noalias() = yaw_free_.mixing() * without_yaw;
  ShiftInterval yaw_room = room_along_yaw(free_commands);
  if (yaw_room.empty()) {
    // No yaw at all fits: desaturate roll, pitch and thrust in their own
    // priority order on the yaw-free basis, then the room for yaw again.
    yaw_free_.allocate(without_yaw, free_commands);
    yaw_room = room_along_yaw(free_commands);
  }
  const double produced_yaw = effectiveness_.row(index(Axis::kYaw)).dot(free_commands);
  const double wanted = demand[index(Axis::kYaw)] - produced_yaw;
  const double gain = yaw_room.empty() ? 0.0 : std::clamp(wanted, yaw_room.lo, yaw_room.hi);
  free_commands += gain * yaw_alone_;
  for (Eigen::Index i = 0; i < free_commands.size(); ++i) {
    free_commands[i] = std::clamp(free_commands[i], range_.lower, range_.upper);
  }
  const AllocationResult yielded =
      describe_allocation(effectiveness_, demand, free_commands, cycle_constants_);
  const bool yielded_better = PrioritizedAllocator::closer_in_priority_order(
      yielded.unallocated, full.unallocated, kCandidateTie);
  const AllocationResult& best = yielded_better ? yielded : full;
  if (yielded_better && holds_roll_pitch_thrust(yielded.unallocated)) {
    commands = free_commands;
    return yielded;
  }
  MotorVector solved;
  const AllocationResult searched = least_squares_.allocate(demand, solved);
  if (PrioritizedAllocator::closer_in_priority_order(searched.unallocated, best.unallocated,
                                                     kCandidateTie)) {
    commands = solved;
    return searched;
  }
  if (yielded_better) commands = free_commands;
  return best;
}

}  // namespace motormix
