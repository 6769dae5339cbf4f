#pragma once
// Motor counts the per-cycle kernels are compiled for. Matrices keep a
// dynamic size with a fixed capacity (so one type serves 1..16 motors), but
// their storage is contiguous, so a kernel can view it at a size known at
// compile time: the products unroll and vectorize like a bare fixed-size
// product. Quads, hexas and octos, the vehicles flown most, get their own
// instantiation in every strategy; clip and shift also at 10, 12, 14 and 16
// motors; any other count runs the same code at dynamic size.

#include <motormix/axes.hpp>
#include <motormix/effectiveness/effectiveness.hpp>
#include <motormix/motor_vector.hpp>

#include <Eigen/Core>

#include <type_traits>
#include <utility>

// For the small steps of a kernel that must not become calls: a call passes
// the per-motor vectors through memory, on the critical path of a chain of
// dependent steps.
#if defined(__GNUC__)
#define MOTORMIX_ALWAYS_INLINE __attribute__((always_inline)) inline
// The same for a lambda (after its parameter list): a kernel passed to
// with_motor_count is inlined into the switch, not called from it.
#define MOTORMIX_INLINE_LAMBDA __attribute__((always_inline))
#else
#define MOTORMIX_ALWAYS_INLINE inline
#define MOTORMIX_INLINE_LAMBDA
#endif

namespace motormix::detail {

// One count's kernel out of line: the dynamic size (its loops have
// remainders) and the fixed counts above eight. Their code is large, and
// inlined it would make every call save registers for it (seen: 1.6x the
// quad's time). Each count has its own function: in one shared function the
// larger counts' registers and stack frame made `shift` at 10 to 16 motors
// 1.4-2x slower.
template <int N, typename Kernel, typename... Args>
#if defined(__GNUC__)
__attribute__((noinline))
#endif
decltype(auto)
at_size_out_of_line(Kernel& kernel, Args&&... args) {
  return kernel(std::integral_constant<int, N>{}, std::forward<Args>(args)...);
}

// The motor counts with a kernel of their own. Quads, hexas and octos in
// every strategy. The even counts from 10 to 16 only for the strategies
// whose kernels are small (clip, shift): four more instantiations grow a
// large kernel's translation unit (prioritized, the report of the others)
// past the compiler's inlining budget, which then calls helpers it inlined
// before (seen: 84 more instructions per quad call of prioritized).
enum class FixedCounts { kUpTo8, kUpTo16 };

// Calls kernel(size, args...) with size the motor count as a compile-time
// constant (Eigen::Dynamic for the counts without their own instantiation).
// Per-cycle callers pass what the kernel needs as arguments to a lambda that
// captures nothing: a capturing lambda's closure is built in memory before
// the switch on every call, for the branches that call out of line and need
// it.
template <FixedCounts kCounts = FixedCounts::kUpTo8, typename Kernel, typename... Args>
MOTORMIX_ALWAYS_INLINE decltype(auto) with_motor_count(Eigen::Index motors, Kernel&& kernel,
                                                       Args&&... args) {
  constexpr bool kUpTo16 = kCounts == FixedCounts::kUpTo16;
  switch (motors) {
    case 4:
      return kernel(std::integral_constant<int, 4>{}, std::forward<Args>(args)...);
    case 6:
      return kernel(std::integral_constant<int, 6>{}, std::forward<Args>(args)...);
    case 8:
      return kernel(std::integral_constant<int, 8>{}, std::forward<Args>(args)...);
    case 10:
      if constexpr (kUpTo16) return at_size_out_of_line<10>(kernel, std::forward<Args>(args)...);
      break;
    case 12:
      if constexpr (kUpTo16) return at_size_out_of_line<12>(kernel, std::forward<Args>(args)...);
      break;
    case 14:
      if constexpr (kUpTo16) return at_size_out_of_line<14>(kernel, std::forward<Args>(args)...);
      break;
    case 16:
      if constexpr (kUpTo16) return at_size_out_of_line<16>(kernel, std::forward<Args>(args)...);
      break;
    default:
      break;
  }
  return at_size_out_of_line<Eigen::Dynamic>(kernel, std::forward<Args>(args)...);
}

// A per-motor vector held locally (in registers where it fits) at N motors.
// Kernels compute into one of these and store the result once: writing
// element by element through a view and reading it back as packets would
// stall on store forwarding.
template <int N>
using LocalMotors =
    Eigen::Matrix<double, N, 1, Eigen::ColMajor, N == Eigen::Dynamic ? kMaxMotors : N, 1>;

// The loop bound at N motors: a constant the compiler unrolls when N is fixed.
template <int N>
constexpr Eigen::Index count(Eigen::Index motors) {
  return N == Eigen::Dynamic ? motors : N;
}

// Views of the contiguous storage at N motors (Eigen::Dynamic: `motors`).
template <int N>
using MotorsView = Eigen::Map<Eigen::Matrix<double, N, 1>>;
template <int N>
using ConstMotorsView = Eigen::Map<const Eigen::Matrix<double, N, 1>>;
// Packet alignment where Eigen gives fixed-capacity matrices aligned
// storage (every vectorized target), none elsewhere.
template <typename Matrix>
inline constexpr int kStorageAlignment = alignof(Matrix) >= 16 ? Eigen::Aligned16
                                                               : Eigen::Unaligned;
// The mixing matrix column by column (MatrixAllocator::mixing_by_column_):
// a product with it is a sum of columns scaled by the demand, packets all
// the way, where the row-major matrix needs a horizontal sum per motor.
template <int N>
using ConstMixingColumnsView =
    Eigen::Map<const Eigen::Matrix<double, N, 4>,
               kStorageAlignment<Eigen::Matrix<double, kMaxMotors, kNumAxes>>,
               Eigen::OuterStride<kMaxMotors>>;
// The effectiveness (4 x motors, column-major): packet-aligned, since an
// EffectivenessMatrix has fixed capacity and 4 rows make each column two
// whole packets.
template <int N>
using ConstEffectivenessView =
    Eigen::Map<const Eigen::Matrix<double, 4, N>, kStorageAlignment<EffectivenessMatrix>>;

}  // namespace motormix::detail
