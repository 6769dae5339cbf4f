// The per-cycle report and clamp kernels (src/core/allocation/report_kernel.hpp) at the
// motor counts with their own instantiation (4 to 16, even: packet code) and
// at dynamic size (scalar code), against the plain definitions: a clamp that
// sends NaN to the lower end, saturation flags within kSaturationTolerance of
// a limit, and what the commands leave undelivered through the
// effectiveness, zero on axes the vehicle does not command.

#include "report_kernel.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace motormix {
namespace {

constexpr CommandRange kRange{0.0, 1.0};
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
// The product by E is summed in a different order by the packet code and
// by this test's loop: agreement to rounding of sums of a few unit terms.
constexpr double kSumRounding = 1e-14;

template <int N>
void check_clamp(Eigen::Index n) {
  const CycleConstants limits(kRange, 0b1111);
  const double inputs[] = {-0.5, 0.0, -0.0, 0.25, 1.0, 1.5, kNaN, kInf, -kInf, 0.999999};
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> pick(0, 9);
  for (int trial = 0; trial < 200; ++trial) {
    detail::LocalMotors<N> u(n);
    for (Eigen::Index i = 0; i < n; ++i) u[i] = inputs[pick(rng)];
    const detail::LocalMotors<N> before = u;
    detail::clamp_into_range<N>(u, limits);
    for (Eigen::Index i = 0; i < n; ++i) {
      const double x = before[i];
      const double expected = std::isnan(x) ? kRange.lower : std::fmin(std::fmax(x, 0.0), 1.0);
      EXPECT_EQ(u[i], expected) << "motor " << i << " of " << n << ", input " << x;
    }
  }
}

// The kernels work in the packets Eigen uses for the same vectors: two
// doubles at the SSE2 baseline, four with AVX where the motor count is a
// multiple of four, eight with AVX-512 where it is a multiple of eight. The
// x86-64-v3 and x86-64-v4 builds of these tests (simd_kernel_tests,
// simd512_kernel_tests) check they run the wide paths at all.
TEST(ReportKernel, PacketWidthFollowsEigen) {
#if defined(MOTORMIX_EXPECT_AVX512)
  EXPECT_EQ(detail::kLanes<4>, 4);
  EXPECT_EQ(detail::kLanes<8>, 8);
  EXPECT_EQ(detail::kLanes<12>, 4);
  EXPECT_EQ(detail::kLanes<16>, 8);
  EXPECT_EQ(detail::kLanes<6>, 2);
  EXPECT_EQ(detail::kLanes<14>, 2);
#elif defined(MOTORMIX_EXPECT_AVX)
  EXPECT_EQ(detail::kLanes<4>, 4);
  EXPECT_EQ(detail::kLanes<8>, 4);
  EXPECT_EQ(detail::kLanes<16>, 4);
#elif defined(__SSE2__) && !defined(__AVX__)
  EXPECT_EQ(detail::kLanes<4>, 2);
  EXPECT_EQ(detail::kLanes<8>, 2);
#endif
#if defined(__SSE2__) && !defined(__AVX512F__)
  EXPECT_EQ(detail::kLanes<6>, 2);  // four does not divide six: pairs, as Eigen does
  EXPECT_EQ(detail::kLanes<14>, 2);
#endif
  EXPECT_EQ(detail::kLanes<Eigen::Dynamic>, 1);
}

TEST(ReportKernel, ClampSendsNanToTheLowerEndAtEveryMotorCount) {
  check_clamp<4>(4);
  check_clamp<6>(6);
  check_clamp<8>(8);
  check_clamp<10>(10);
  check_clamp<12>(12);
  check_clamp<14>(14);
  check_clamp<16>(16);
  for (Eigen::Index n : {1, 3, 5, 10, 16}) check_clamp<Eigen::Dynamic>(n);
}

template <int N>
void check_report(Eigen::Index n, AxisMask controlled) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> entry(-1.0, 1.0);
  std::uniform_real_distribution<double> command(-0.1, 1.1);
  const CycleConstants limits(kRange, controlled);
  for (int trial = 0; trial < 500; ++trial) {
    EffectivenessMatrix e(kNumAxes, n);
    for (Eigen::Index j = 0; j < n; ++j) {
      for (int a = 0; a < kNumAxes; ++a) e(a, j) = entry(rng);
    }
    AxisVector target;
    for (int a = 0; a < kNumAxes; ++a) target[a] = entry(rng);
    detail::LocalMotors<N> u(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      // Some exactly on a limit, some within the saturation tolerance.
      const int kind = trial % 5;
      u[i] = kind == 0 ? (i % 2 ? 1.0 : 0.0)
                       : (kind == 1 ? 1.0 - 0.5 * detail::kSaturationTolerance : command(rng));
      u[i] = std::fmin(std::fmax(u[i], 0.0), 1.0);
    }
    const AllocationResult r = detail::describe_fixed<N>(e, target, u.data(), n, limits);
    MotorMask upper = 0;
    MotorMask lower = 0;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (u[i] >= 1.0 - detail::kSaturationTolerance) upper |= MotorMask{1} << i;
      if (u[i] <= 0.0 + detail::kSaturationTolerance) lower |= MotorMask{1} << i;
    }
    EXPECT_EQ(r.saturated_upper, upper);
    EXPECT_EQ(r.saturated_lower, lower);
    std::uint8_t limited = 0;
    for (int a = 0; a < kNumAxes; ++a) {
      if (!((controlled >> a) & 1U)) {
        EXPECT_EQ(r.unallocated[a], 0.0) << "axis " << a << " is not commanded";
        EXPECT_FALSE(std::signbit(r.unallocated[a]));
        continue;
      }
      double produced = 0.0;
      for (Eigen::Index j = 0; j < n; ++j) produced += e(a, j) * u[j];
      EXPECT_NEAR(r.unallocated[a], target[a] - produced, kSumRounding);
      if (std::abs(r.unallocated[a]) > kDeliveredTolerance) limited |= std::uint8_t(1U << a);
    }
    EXPECT_EQ(r.axis_limited, limited);
    EXPECT_EQ(r.iterations, 0);
  }
}

TEST(ReportKernel, FlagsAndUndeliveredDemandAtEveryMotorCount) {
  // All axes (a multirotor), and yaw and thrust only (a ground vehicle).
  for (AxisMask controlled : {AxisMask{0b1111}, AxisMask{0b1100}}) {
    check_report<4>(4, controlled);
    check_report<6>(6, controlled);
    check_report<8>(8, controlled);
    check_report<10>(10, controlled);
    check_report<12>(12, controlled);
    check_report<14>(14, controlled);
    check_report<16>(16, controlled);
    for (Eigen::Index n : {2, 3, 5, 12, 16}) check_report<Eigen::Dynamic>(n, controlled);
  }
}

}  // namespace
}  // namespace motormix
