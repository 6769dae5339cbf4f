#pragma once
// The report every matrix strategy returns (saturation flags and what was not
// delivered), as a kernel at a motor count fixed at compile time. Shared by
// the strategies' own fixed-size paths.

#include <motormix/allocation/allocation.hpp>

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

// The few operations of one SIMD width the kernels below use, so that each
// kernel is written once for every width: Packet<2> (SSE2), Packet<4> (AVX),
// Packet<8> (AVX-512). `splat` takes a CycleConstants entry, a value stored
// twice: SSE2 loads it as a whole packet (the baseline has no broadcasting
// load), the wider ones broadcast it. max and min keep the instruction's
// operand order: where either operand is NaN, the second one is returned.
template <int Lanes>
struct Packet;
#if defined(__SSE2__)
template <>
struct Packet<2> {
  using V = __m128d;
  MOTORMIX_ALWAYS_INLINE static V splat(const double* twice) { return _mm_load_pd(twice); }
  MOTORMIX_ALWAYS_INLINE static V load(const double* p) { return _mm_loadu_pd(p); }
  MOTORMIX_ALWAYS_INLINE static void store(double* p, V v) { _mm_storeu_pd(p, v); }
  MOTORMIX_ALWAYS_INLINE static V max(V a, V b) { return _mm_max_pd(a, b); }
  MOTORMIX_ALWAYS_INLINE static V min(V a, V b) { return _mm_min_pd(a, b); }
  MOTORMIX_ALWAYS_INLINE static V and_not(V mask, V v) { return _mm_andnot_pd(mask, v); }
  MOTORMIX_ALWAYS_INLINE static unsigned at_least(V a, V b) {
    return unsigned(_mm_movemask_pd(_mm_cmpge_pd(a, b)));
  }
  MOTORMIX_ALWAYS_INLINE static unsigned at_most(V a, V b) {
    return unsigned(_mm_movemask_pd(_mm_cmple_pd(a, b)));
  }
  MOTORMIX_ALWAYS_INLINE static unsigned above(V a, V b) {
    return unsigned(_mm_movemask_pd(_mm_cmpgt_pd(a, b)));
  }
};
#endif
#if defined(__AVX__)
template <>
struct Packet<4> {
  using V = __m256d;
  MOTORMIX_ALWAYS_INLINE static V splat(const double* twice) { return _mm256_broadcast_sd(twice); }
  MOTORMIX_ALWAYS_INLINE static V load(const double* p) { return _mm256_loadu_pd(p); }
  MOTORMIX_ALWAYS_INLINE static void store(double* p, V v) { _mm256_storeu_pd(p, v); }
  MOTORMIX_ALWAYS_INLINE static V max(V a, V b) { return _mm256_max_pd(a, b); }
  MOTORMIX_ALWAYS_INLINE static V min(V a, V b) { return _mm256_min_pd(a, b); }
  MOTORMIX_ALWAYS_INLINE static V and_not(V mask, V v) { return _mm256_andnot_pd(mask, v); }
  MOTORMIX_ALWAYS_INLINE static unsigned at_least(V a, V b) {
    return unsigned(_mm256_movemask_pd(_mm256_cmp_pd(a, b, _CMP_GE_OQ)));
  }
  MOTORMIX_ALWAYS_INLINE static unsigned at_most(V a, V b) {
    return unsigned(_mm256_movemask_pd(_mm256_cmp_pd(a, b, _CMP_LE_OQ)));
  }
  MOTORMIX_ALWAYS_INLINE static unsigned above(V a, V b) {
    return unsigned(_mm256_movemask_pd(_mm256_cmp_pd(a, b, _CMP_GT_OQ)));
  }
};
#endif
#if defined(__AVX512F__)
template <>
struct Packet<8> {
  using V = __m512d;
  MOTORMIX_ALWAYS_INLINE static V splat(const double* twice) { return _mm512_set1_pd(*twice); }
  MOTORMIX_ALWAYS_INLINE static V load(const double* p) { return _mm512_loadu_pd(p); }
  MOTORMIX_ALWAYS_INLINE static void store(double* p, V v) { _mm512_storeu_pd(p, v); }
  MOTORMIX_ALWAYS_INLINE static V max(V a, V b) { return _mm512_max_pd(a, b); }
  MOTORMIX_ALWAYS_INLINE static V min(V a, V b) { return _mm512_min_pd(a, b); }
  MOTORMIX_ALWAYS_INLINE static unsigned at_least(V a, V b) {
    return _mm512_cmp_pd_mask(a, b, _CMP_GE_OQ);
  }
  MOTORMIX_ALWAYS_INLINE static unsigned at_most(V a, V b) {
    return _mm512_cmp_pd_mask(a, b, _CMP_LE_OQ);
  }
};
#endif

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
// `lower`; the scalar loop says the same. `Motors`: LocalMotors<N>, or a
// MotorsView<N> of commands already stored.
template <int N, typename Motors>
MOTORMIX_ALWAYS_INLINE void clamp_into_range(Motors& u, const CycleConstants& limits) {
  constexpr int kWidth = kLanes<N>;
  if constexpr (kWidth > 1) {
    using P = Packet<kWidth>;
    const typename P::V lower = P::splat(limits.lower);
    const typename P::V upper = P::splat(limits.upper);
    for (int i = 0; i < N; i += kWidth) {
      P::store(u.data() + i, P::min(P::max(P::load(u.data() + i), lower), upper));
    }
    return;
  }
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
  constexpr int kWidth = kLanes<N>;
  if constexpr (kWidth > 1) {
    // A packet of motors per compare, their flags by movemask: the flags
    // cost a few instructions instead of two compares and shifts per motor.
    using P = Packet<kWidth>;
    const typename P::V top = P::splat(limits.at_upper);
    const typename P::V bottom = P::splat(limits.at_lower);
    for (int i = 0; i < N; i += kWidth) {
      const typename P::V packet = P::load(commands + i);
      upper |= static_cast<MotorMask>(P::at_least(packet, top) << i);
      lower |= static_cast<MotorMask>(P::at_most(packet, bottom) << i);
    }
    // The four axes in the packets Eigen wrote `unallocated` with.
    constexpr int kAxisWidth = kLanes<kNumAxes>;
    using A = Packet<kAxisWidth>;
    const typename A::V tolerance = A::splat(limits.delivered);
    const typename A::V sign = A::splat(limits.sign);  // the sign bit, cleared by and_not
    for (int a = 0; a < kNumAxes; a += kAxisWidth) {
      const typename A::V magnitude = A::and_not(sign, A::load(unallocated.data() + a));
      limited |= static_cast<std::uint8_t>(A::above(magnitude, tolerance) << a);
    }
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
