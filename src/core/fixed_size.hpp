#pragma once
// Motor counts the per-cycle kernels are compiled for. Matrices keep a
// dynamic size with a fixed capacity (so one type serves 1..16 motors), but
// their storage is contiguous, so a kernel can view it at a size known at
// compile time: the products unroll and vectorize like a bare fixed-size
// product. Quads, hexas and octos, the vehicles flown most, get their own
// instantiation; any other count runs the same code at dynamic size.

#include <motormix/motor_vector.hpp>

#include <Eigen/Core>

#include <type_traits>

// For the small steps of a kernel that must not become calls: a call passes
// the per-motor vectors through memory, on the critical path of a chain of
// dependent steps.
#if defined(__GNUC__)
#define MOTORMIX_ALWAYS_INLINE __attribute__((always_inline)) inline
#else
#define MOTORMIX_ALWAYS_INLINE inline
#endif

namespace motormix::detail {

template <typename Kernel>
decltype(auto) with_motor_count(Eigen::Index motors, Kernel&& kernel) {
  switch (motors) {
    case 4:
      return kernel(std::integral_constant<int, 4>{});
    case 6:
      return kernel(std::integral_constant<int, 6>{});
    case 8:
      return kernel(std::integral_constant<int, 8>{});
    default:
      return kernel(std::integral_constant<int, Eigen::Dynamic>{});
  }
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
// The mixing matrix column by column (MatrixAllocator::mixing_by_column_):
// a product with it is a sum of columns scaled by the demand, packets all
// the way, where the row-major matrix needs a horizontal sum per motor.
template <int N>
using ConstMixingColumnsView =
    Eigen::Map<const Eigen::Matrix<double, N, 4>, Eigen::Aligned16, Eigen::OuterStride<kMaxMotors>>;
template <int N>
using ConstEffectivenessView = Eigen::Map<const Eigen::Matrix<double, 4, N>>;

}  // namespace motormix::detail
