#include <motormix/allocation.hpp>

#include <cmath>

namespace motormix {

namespace {
// A command within this distance of a limit counts as sitting on it.
constexpr double kSaturationTolerance = 1e-9;
}  // namespace

AllocationResult describe_allocation(const EffectivenessMatrix& effectiveness,
                                     const AxisVector& target, const MotorVector& commands,
                                     CommandRange range) {
  AllocationResult result;
  for (Eigen::Index i = 0; i < commands.size(); ++i) {
    if (commands[i] >= range.upper - kSaturationTolerance) {
      result.saturated_upper |= MotorMask{1} << i;
    }
    if (commands[i] <= range.lower + kSaturationTolerance) {
      result.saturated_lower |= MotorMask{1} << i;
    }
  }
  const AxisVector produced = effectiveness * commands;
  result.unallocated = target - produced;
  for (int a = 0; a < kNumAxes; ++a) {
    if (std::abs(result.unallocated[a]) > kDeliveredTolerance) {
      result.axis_limited |= static_cast<std::uint8_t>(1U << a);
    }
  }
  return result;
}

}  // namespace motormix
