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

// Inlined into each caller: the report is most of a simple strategy's cost,
// and a call would pass the result through memory.
template <int N>
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
inline AllocationResult
describe_fixed(const EffectivenessMatrix& effectiveness, const AxisVector& target,
               const double* commands, Eigen::Index n, CommandRange range, AxisMask controlled) {
  const detail::ConstMotorsView<N> u(commands, n);
  const detail::ConstEffectivenessView<N> e(effectiveness.data(), kNumAxes, n);
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
  result.unallocated.noalias() = target - e * u;
  std::uint8_t limited = 0;
  for (int a = 0; a < kNumAxes; ++a) {
    if (!((controlled >> a) & 1U)) result.unallocated[a] = 0.0;
    limited |=
        static_cast<std::uint8_t>((std::abs(result.unallocated[a]) > kDeliveredTolerance) << a);
  }
  result.axis_limited = limited;
  return result;
}

}  // namespace motormix::detail
