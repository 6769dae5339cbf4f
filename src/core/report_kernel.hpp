#pragma once
// The report every matrix strategy returns (saturation flags and what was not
// delivered), as a kernel at a motor count fixed at compile time. Shared by
// the strategies' own fixed-size paths.

#include <motormix/allocation.hpp>

#include "fixed_size.hpp"

#include <cmath>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

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
  AllocationResult result;
  MotorMask upper = 0;
  MotorMask lower = 0;
  const double top = range.upper - kSaturationTolerance;
  const double bottom = range.lower + kSaturationTolerance;
  std::uint8_t limited = 0;
#if defined(__SSE2__)
  constexpr bool kPairs = N != Eigen::Dynamic && N % 2 == 0;
#else
  constexpr bool kPairs = false;
#endif
  if constexpr (kPairs) {
#if defined(__SSE2__)
    // Two motors per compare, their flags by movemask: the flags cost a
    // few instructions instead of two compares and shifts per motor.
    const __m128d top2 = _mm_set1_pd(top);
    const __m128d bottom2 = _mm_set1_pd(bottom);
    for (int i = 0; i < N; i += 2) {
      const __m128d pair = _mm_loadu_pd(commands + i);
      upper |= static_cast<MotorMask>(_mm_movemask_pd(_mm_cmpge_pd(pair, top2))) << i;
      lower |= static_cast<MotorMask>(_mm_movemask_pd(_mm_cmple_pd(pair, bottom2))) << i;
    }
    const __m128d tolerance = _mm_set1_pd(kDeliveredTolerance);
    const __m128d magnitude = _mm_set1_pd(-0.0);  // the sign bit, cleared by andnot
    const __m128d low_axes = _mm_andnot_pd(magnitude, _mm_loadu_pd(unallocated.data()));
    const __m128d high_axes = _mm_andnot_pd(magnitude, _mm_loadu_pd(unallocated.data() + 2));
    limited = static_cast<std::uint8_t>(_mm_movemask_pd(_mm_cmpgt_pd(low_axes, tolerance)) |
                                        _mm_movemask_pd(_mm_cmpgt_pd(high_axes, tolerance)) << 2);
#endif
  } else {
    const detail::ConstMotorsView<N> u(commands, n);
    for (Eigen::Index i = 0; i < detail::count<N>(n); ++i) {
      upper |= static_cast<MotorMask>(u[i] >= top) << i;
      lower |= static_cast<MotorMask>(u[i] <= bottom) << i;
    }
    for (int a = 0; a < kNumAxes; ++a) {
      limited |= static_cast<std::uint8_t>((std::abs(unallocated[a]) > kDeliveredTolerance) << a);
    }
  }
  result.saturated_upper = upper;
  result.saturated_lower = lower;
  result.unallocated = unallocated;
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
