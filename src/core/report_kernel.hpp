#pragma once
// The report every matrix strategy returns (saturation flags and what was not
// delivered), as a kernel at a motor count fixed at compile time. Shared by
// the strategies' own fixed-size paths.

#include <motormix/allocation.hpp>

#include "fixed_size.hpp"

#include <cmath>

namespace motormix::detail {

// A command within this distance of a limit counts as sitting on it.
inline constexpr double kSaturationTolerance = 1e-9;

// What `commands` leave undelivered of `target`, per axis; axes the vehicle
// is not commanded in are zero.
template <int N>
MOTORMIX_ALWAYS_INLINE AxisVector undelivered(const EffectivenessMatrix& effectiveness,
                                              const AxisVector& target, const double* commands,
                                              Eigen::Index n, AxisMask controlled) {
  const detail::ConstMotorsView<N> u(commands, n);
  const detail::ConstEffectivenessView<N> e(effectiveness.data(), kNumAxes, n);
  AxisVector unallocated;
  unallocated.noalias() = target - e * u;
  for (int a = 0; a < kNumAxes; ++a) {
    if (!((controlled >> a) & 1U)) unallocated[a] = 0.0;
  }
  return unallocated;
}

// The report for `commands`, given what they leave undelivered.
template <int N>
MOTORMIX_ALWAYS_INLINE AllocationResult describe_with(const AxisVector& unallocated,
                                                      const double* commands, Eigen::Index n,
                                                      CommandRange range) {
  const detail::ConstMotorsView<N> u(commands, n);
  AllocationResult result;
  MotorMask upper = 0;
  MotorMask lower = 0;
  const double top = range.upper - kSaturationTolerance;
  const double bottom = range.lower + kSaturationTolerance;
  for (Eigen::Index i = 0; i < detail::count<N>(n); ++i) {
    upper |= static_cast<MotorMask>(u[i] >= top) << i;
    lower |= static_cast<MotorMask>(u[i] <= bottom) << i;
  }
  result.saturated_upper = upper;
  result.saturated_lower = lower;
  result.unallocated = unallocated;
  std::uint8_t limited = 0;
  for (int a = 0; a < kNumAxes; ++a) {
    limited |= static_cast<std::uint8_t>((std::abs(unallocated[a]) > kDeliveredTolerance) << a);
  }
  result.axis_limited = limited;
  return result;
}

// Inlined into each caller: the report is most of a simple strategy's cost,
// and a call would pass the result through memory.
template <int N>
MOTORMIX_ALWAYS_INLINE AllocationResult describe_fixed(const EffectivenessMatrix& effectiveness,
                                                       const AxisVector& target,
                                                       const double* commands, Eigen::Index n,
                                                       CommandRange range, AxisMask controlled) {
  return describe_with<N>(undelivered<N>(effectiveness, target, commands, n, controlled), commands,
                          n, range);
}

}  // namespace motormix::detail
