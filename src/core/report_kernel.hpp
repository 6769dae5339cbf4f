#pragma once
// The report every matrix strategy returns (saturation flags and what was not
// delivered), as a kernel at a motor count fixed at compile time. Shared by
// the strategies' own fixed-size paths.

#include <motormix/allocation.hpp>

#include "fixed_size.hpp"

#include <cmath>

#if defined(__AVX__)
#include <immintrin.h>
#elif defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace motormix::detail {

// A command within this distance of a limit counts as sitting on it.
inline constexpr double kSaturationTolerance = 1e-9;

// Motors per SIMD packet in the kernels below at N motors: the packet Eigen
// itself uses for an N-vector of doubles (the widest the target has whose
// size divides N); 1, the scalar loops, at the dynamic size and where the
// kernels have no packet code (targets without SSE2). The kernels write and
// read the vectors Eigen reads and wrote at the same width: a packet stored
// as two halves and loaded whole stalls the load on store forwarding (seen
// with AVX before the kernels followed Eigen: `clip` and `shift` twice as
// slow as at the SSE2 baseline).
template <int N>
constexpr int lanes() {
#if defined(__SSE2__)
  if constexpr (N != Eigen::Dynamic) {
    using Packet = typename Eigen::internal::find_best_packet<double, N>::type;
    return Eigen::internal::unpacket_traits<Packet>::size;
  }
#endif
  return 1;
}
template <int N>
inline constexpr int kLanes = lanes<N>();

// `left` on the controlled axes, zero on the others (roll and pitch of a
// wheeled vehicle): a bitwise and with the prepared mask, no branch and no
// trip through memory.
MOTORMIX_ALWAYS_INLINE AxisVector on_controlled_axes(const AxisVector& left,
                                                     const CycleConstants& limits) {
  AxisVector kept;
#if defined(__AVX__)
  // One packet of four, as Eigen reads an AxisVector here (see kLanes).
  _mm256_storeu_pd(
      kept.data(),
      _mm256_and_pd(_mm256_loadu_pd(left.data()),
                    _mm256_loadu_pd(reinterpret_cast<const double*>(limits.axis_kept))));
#elif defined(__SSE2__)
  const __m128i* keep = reinterpret_cast<const __m128i*>(limits.axis_kept);
  _mm_store_pd(kept.data(),
               _mm_and_pd(_mm_load_pd(left.data()), _mm_castsi128_pd(_mm_load_si128(keep))));
  _mm_store_pd(kept.data() + 2, _mm_and_pd(_mm_load_pd(left.data() + 2),
                                           _mm_castsi128_pd(_mm_load_si128(keep + 1))));
#else
  for (int a = 0; a < kNumAxes; ++a) kept[a] = limits.axis_kept[a] ? left[a] : 0.0;
#endif
  return kept;
}

// u into the command range, a NaN (which finite inputs cannot produce) to
// the lower end, the safe one. maxpd(u, lower) gives its second operand
// unless u is greater, so a NaN (and a -0 at a lower limit of 0) becomes
// `lower`; the scalar loop says the same.
template <int N>
MOTORMIX_ALWAYS_INLINE void clamp_into_range(LocalMotors<N>& u, const CycleConstants& limits) {
#if defined(__AVX512F__)
  if constexpr (kLanes<N> == 8) {
    const __m512d lower = _mm512_set1_pd(limits.lower[0]);
    const __m512d upper = _mm512_set1_pd(limits.upper[0]);
    for (int i = 0; i < N; i += 8) {
      _mm512_storeu_pd(u.data() + i,
                       _mm512_min_pd(_mm512_max_pd(_mm512_loadu_pd(u.data() + i), lower), upper));
    }
    return;
  }
#endif
#if defined(__AVX__)
  if constexpr (kLanes<N> == 4) {
    const __m256d lower = _mm256_broadcast_sd(limits.lower);
    const __m256d upper = _mm256_broadcast_sd(limits.upper);
    for (int i = 0; i < N; i += 4) {
      _mm256_storeu_pd(u.data() + i,
                       _mm256_min_pd(_mm256_max_pd(_mm256_loadu_pd(u.data() + i), lower), upper));
    }
    return;
  }
#endif
#if defined(__SSE2__)
  if constexpr (kLanes<N> == 2) {
    const __m128d lower = _mm_load_pd(limits.lower);
    const __m128d upper = _mm_load_pd(limits.upper);
    for (int i = 0; i < N; i += 2) {
      _mm_storeu_pd(u.data() + i, _mm_min_pd(_mm_max_pd(_mm_loadu_pd(u.data() + i), lower), upper));
    }
    return;
  }
#endif
  const double lower = limits.lower[0];
  const double upper = limits.upper[0];
  for (Eigen::Index i = 0; i < u.size(); ++i) {
    const double above = u[i] > lower ? u[i] : lower;
    u[i] = above < upper ? above : upper;
  }
}

// What `commands` leave undelivered of `target`, per axis; axes the vehicle
// is not commanded in are zero.
template <int N>
MOTORMIX_ALWAYS_INLINE AxisVector undelivered(const EffectivenessMatrix& effectiveness,
                                              const AxisVector& target, const double* commands,
                                              Eigen::Index n, const CycleConstants& limits) {
  const detail::ConstMotorsView<N> u(commands, n);
  // An EffectivenessMatrix's storage is packet-aligned (fixed capacity).
  const detail::ConstEffectivenessView<N> e(effectiveness.data(), kNumAxes, n);
  AxisVector left;
  left.noalias() = target - e * u;
  return on_controlled_axes(left, limits);
}

// The report for `commands`, given what they leave undelivered.
template <int N>
MOTORMIX_ALWAYS_INLINE AllocationResult describe_with(const AxisVector& unallocated,
                                                      const double* commands, Eigen::Index n,
                                                      const CycleConstants& limits) {
  MotorMask upper = 0;
  MotorMask lower = 0;
  std::uint8_t limited = 0;
  if constexpr (lanes<N>() > 1) {
    // A packet of motors per compare, their flags by movemask: the flags
    // cost a few instructions instead of two compares and shifts per motor.
#if defined(__AVX512F__)
    if constexpr (kLanes<N> == 8) {
      const __m512d top = _mm512_set1_pd(limits.at_upper[0]);
      const __m512d bottom = _mm512_set1_pd(limits.at_lower[0]);
      for (int i = 0; i < N; i += 8) {
        const __m512d packet = _mm512_loadu_pd(commands + i);
        upper |= static_cast<MotorMask>(_mm512_cmp_pd_mask(packet, top, _CMP_GE_OQ)) << i;
        lower |= static_cast<MotorMask>(_mm512_cmp_pd_mask(packet, bottom, _CMP_LE_OQ)) << i;
      }
    }
#endif
#if defined(__AVX__)
    if constexpr (kLanes<N> == 4) {
      const __m256d top = _mm256_broadcast_sd(limits.at_upper);
      const __m256d bottom = _mm256_broadcast_sd(limits.at_lower);
      for (int i = 0; i < N; i += 4) {
        const __m256d packet = _mm256_loadu_pd(commands + i);
        upper |= static_cast<MotorMask>(_mm256_movemask_pd(_mm256_cmp_pd(packet, top, _CMP_GE_OQ)))
                 << i;
        lower |=
            static_cast<MotorMask>(_mm256_movemask_pd(_mm256_cmp_pd(packet, bottom, _CMP_LE_OQ)))
            << i;
      }
    }
#endif
#if defined(__SSE2__)
    if constexpr (kLanes<N> == 2) {
      const __m128d top2 = _mm_load_pd(limits.at_upper);
      const __m128d bottom2 = _mm_load_pd(limits.at_lower);
      for (int i = 0; i < N; i += 2) {
        const __m128d pair = _mm_loadu_pd(commands + i);
        upper |= static_cast<MotorMask>(_mm_movemask_pd(_mm_cmpge_pd(pair, top2))) << i;
        lower |= static_cast<MotorMask>(_mm_movemask_pd(_mm_cmple_pd(pair, bottom2))) << i;
      }
    }
#endif
#if defined(__AVX__)
    // The four axes as one packet, as Eigen wrote `unallocated`.
    const __m256d tolerance = _mm256_broadcast_sd(limits.delivered);
    const __m256d magnitude = _mm256_broadcast_sd(limits.sign);  // the sign bit, cleared by andnot
    const __m256d axes = _mm256_andnot_pd(magnitude, _mm256_loadu_pd(unallocated.data()));
    limited =
        static_cast<std::uint8_t>(_mm256_movemask_pd(_mm256_cmp_pd(axes, tolerance, _CMP_GT_OQ)));
#elif defined(__SSE2__)
    const __m128d tolerance = _mm_load_pd(limits.delivered);
    const __m128d magnitude = _mm_load_pd(limits.sign);  // the sign bit, cleared by andnot
    const __m128d low_axes = _mm_andnot_pd(magnitude, _mm_loadu_pd(unallocated.data()));
    const __m128d high_axes = _mm_andnot_pd(magnitude, _mm_loadu_pd(unallocated.data() + 2));
    limited = static_cast<std::uint8_t>(_mm_movemask_pd(_mm_cmpgt_pd(low_axes, tolerance)) |
                                        _mm_movemask_pd(_mm_cmpgt_pd(high_axes, tolerance)) << 2);
#endif
  } else {
    const detail::ConstMotorsView<N> u(commands, n);
    const double top = limits.at_upper[0];
    const double bottom = limits.at_lower[0];
    for (Eigen::Index i = 0; i < detail::count<N>(n); ++i) {
      upper |= static_cast<MotorMask>(u[i] >= top) << i;
      lower |= static_cast<MotorMask>(u[i] <= bottom) << i;
    }
    for (int a = 0; a < kNumAxes; ++a) {
      limited |= static_cast<std::uint8_t>((std::abs(unallocated[a]) > kDeliveredTolerance) << a);
    }
  }
  AllocationResult result;
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
                                                       const CycleConstants& limits) {
  return describe_with<N>(undelivered<N>(effectiveness, target, commands, n, limits), commands, n,
                          limits);
}

}  // namespace motormix::detail
