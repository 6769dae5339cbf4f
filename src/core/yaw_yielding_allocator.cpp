#include <motormix/yaw_yielding_allocator.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace motormix {

namespace {
// Below this (normalized units) an axis counts as delivered.
constexpr double kHeld = kDeliveredTolerance;

bool holds_roll_pitch_thrust(const AxisVector& unallocated) {
  return std::abs(unallocated[index(Axis::kRoll)]) <= kHeld &&
         std::abs(unallocated[index(Axis::kPitch)]) <= kHeld &&
         std::abs(unallocated[index(Axis::kThrust)]) <= kHeld;
}
}  // namespace

YawYieldingAllocator::YawYieldingAllocator(const MixingBasis& reduced,
                                           const MixingMatrix& yaw_free, CommandRange range,
                                           Airmode airmode, double yaw_headroom)
    : full_(reduced, range, airmode, yaw_headroom),
      yaw_free_(MixingBasis(yaw_free, reduced.effectiveness, reduced.controlled), range, airmode,
                yaw_headroom),
      yaw_alone_(yaw_free.col(index(Axis::kYaw))),
      effectiveness_(reduced.effectiveness),
      range_(range),
      controlled_(reduced.controlled) {}

AllocationResult YawYieldingAllocator::allocate(const AxisVector& demand,
                                                MotorVector& commands) const {
  const AllocationResult full = full_.allocate(demand, commands);
  if (holds_roll_pitch_thrust(full.unallocated)) return full;

  // Roll, pitch and thrust with yaw free...
  AxisVector without_yaw = demand;
  without_yaw[index(Axis::kYaw)] = 0.0;
  MotorVector free_commands;
  yaw_free_.allocate(without_yaw, free_commands);
  // ...then the demanded yaw, as far as the range allows, along the
  // direction that changes nothing else.
  const double produced_yaw = effectiveness_.row(index(Axis::kYaw)).dot(free_commands);
  const double wanted = demand[index(Axis::kYaw)] - produced_yaw;
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  for (Eigen::Index i = 0; i < free_commands.size(); ++i) {
    const double d = yaw_alone_[i];
    if (std::abs(d) < std::numeric_limits<double>::epsilon()) continue;
    const double a = (range_.lower - free_commands[i]) / d;
    const double b = (range_.upper - free_commands[i]) / d;
    lo = std::max(lo, std::min(a, b));
    hi = std::min(hi, std::max(a, b));
  }
  const double gain = lo <= hi ? std::clamp(wanted, lo, hi) : 0.0;
  free_commands += gain * yaw_alone_;
  for (Eigen::Index i = 0; i < free_commands.size(); ++i) {
    free_commands[i] = std::clamp(free_commands[i], range_.lower, range_.upper);
  }
  const AllocationResult yielded =
      describe_allocation(effectiveness_, demand, free_commands, range_, controlled_);
  if (PrioritizedAllocator::closer_in_priority_order(yielded.unallocated, full.unallocated)) {
    commands = free_commands;
    return yielded;
  }
  return full;
}

}  // namespace motormix
