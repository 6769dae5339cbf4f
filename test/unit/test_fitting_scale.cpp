// The repair's one-dimensional problem (src/core/fitting_scale.hpp) against
// an independent reference: every pair of motors turned into a bound on s,
// the way it is derived on paper. The reference is O(n^2) and divides; the
// kernels step along the pieces of a convex excess. Random bases, parts and
// thrust columns (with motors the shift cannot move, and with equal lift),
// seeded; both airmodes (thrust may rise or not); 4, 6, 8 motors at fixed
// size and 5, 12, 16 at dynamic size.

#include <motormix/allocation.hpp>

#include "fitting_scale.hpp"
#include "shift_kernel.hpp"

#include <gtest/gtest.h>

#include <random>

namespace motormix {
namespace {

// Scales agree to this (they are tops of intervals bounded by ratios of
// numbers of order one).
constexpr double kScaleTolerance = 1e-9;

// Largest s in [0, 1] for which some shift k (k <= 0 unless may_raise)
// puts every motor of base + s part + k thrust in range; -1 if none.
double pairwise_reference(const MotorVector& base, const MotorVector& part,
                          const MotorVector& thrust, CommandRange r, bool may_raise) {
  double lo = 0.0;
  double hi = 1.0;
  const auto keep = [&](double a, double c) {  // a s <= c
    if (a > 0.0) {
      hi = std::min(hi, c / a);
    } else if (a < 0.0) {
      lo = std::max(lo, c / a);
    } else if (c < 0.0) {
      hi = -1.0;
    }
  };
  const Eigen::Index n = base.size();
  for (Eigen::Index i = 0; i < n; ++i) {
    if (thrust[i] <= 0.0) {
      keep(part[i], r.upper - base[i]);
      keep(-part[i], base[i] - r.lower);
      continue;
    }
    const double rate_i = part[i] / thrust[i];
    const double low_i = (r.lower - base[i]) / thrust[i];
    if (!may_raise) keep(-rate_i, -low_i);
    for (Eigen::Index j = 0; j < n; ++j) {
      if (thrust[j] <= 0.0) continue;
      keep(part[j] / thrust[j] - rate_i, (r.upper - base[j]) / thrust[j] - low_i);
    }
  }
  return lo <= hi ? hi : -1.0;
}

template <int N>
double kernel(const MotorVector& base, const MotorVector& part, const MotorVector& thrust,
              CommandRange r, bool may_raise) {
  const Eigen::Index n = base.size();
  const detail::LocalMotors<N> b = base;
  const detail::LocalMotors<N> p = part;
  const MotorVector lift = detail::positive_inverse(thrust);
  const detail::ConstMotorsView<N> view(lift.data(), n);
  return detail::largest_fitting_scale<N>(b, p, view, thrust.minCoeff() > 0.0, n, r, may_raise);
}

template <int N>
double equal_lift_kernel(const MotorVector& base, const MotorVector& part, CommandRange r,
                         bool may_raise) {
  const detail::LocalMotors<N> b = base;
  const detail::LocalMotors<N> p = part;
  return detail::largest_fitting_scale_equal_lift<N>(b, p, base.size(), r, may_raise);
}

struct Case {
  MotorVector base, part, thrust;
};

Case random_case(std::mt19937_64& rng, int n, bool equal_lift, bool some_fixed) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Case c{MotorVector(n), MotorVector(n), MotorVector(n)};
  const double lift = 0.2 + 0.8 * (unit(rng) + 1.0) / 2.0;
  for (int i = 0; i < n; ++i) {
    c.base[i] = 0.5 + 0.6 * unit(rng);
    c.part[i] = unit(rng);
    c.thrust[i] = equal_lift ? lift : 0.2 + 0.8 * (unit(rng) + 1.0) / 2.0;
  }
  // A motor the shift cannot move (a failed one's column is zero).
  if (some_fixed) c.thrust[static_cast<Eigen::Index>(rng() % static_cast<unsigned>(n))] = 0.0;
  return c;
}

// Whether a shift (only downward unless may_raise) puts every motor of
// base + s part in range, within the rounding the repair allows.
bool shift_fits_at(const Case& c, double s, CommandRange r, bool may_raise) {
  const MotorVector u = c.base + s * c.part;
  const MotorVector lift = detail::positive_inverse(c.thrust);
  ShiftInterval shift =
      detail::with_motor_count(u.size(), [&](auto size) {
        return detail::shifts_that_fit<decltype(size)::value>(u, lift, u.size(), r);
      });
  if (!may_raise) shift.hi = std::min(shift.hi, 0.0);
  constexpr double kRounding = 1e-12;  // as the repair allows
  return shift.hi - shift.lo >= -kRounding;
}

template <int N>
void agree_on_random_cases(int n) {
  std::mt19937_64 rng(0xf17 + static_cast<unsigned>(n));
  const CommandRange r{0.0, 1.0};
  int found = 0;
  int refused = 0;
  int points = 0;  // single fitting points the reference lost
  for (int k = 0; k < 20000; ++k) {
    const bool equal_lift = k % 3 == 0;
    const bool some_fixed = !equal_lift && k % 3 == 1;
    const Case c = random_case(rng, n, equal_lift, some_fixed);
    for (const bool may_raise : {false, true}) {
      const double expected = pairwise_reference(c.base, c.part, c.thrust, r, may_raise);
      const double got = kernel<N>(c.base, c.part, c.thrust, r, may_raise);
      if (expected < 0.0) {
        // No scale fits, or only a single point that the reference's
        // rounding loses: the kernel gives up too, or finds that point.
        if (got >= 0.0) {
          ASSERT_TRUE(shift_fits_at(c, got, r, may_raise)) << "n " << n << " case " << k;
          ++points;
        }
        ++refused;
        continue;
      }
      ++found;
      ASSERT_NEAR(got, expected, kScaleTolerance) << "n " << n << " case " << k << " raise "
                                                  << may_raise;
      if (equal_lift) {
        ASSERT_NEAR(equal_lift_kernel<N>(c.base, c.part, r, may_raise), expected,
                    kScaleTolerance)
            << "equal lift, n " << n << " case " << k;
      }
    }
  }
  // Both outcomes are exercised (more motors fit less often).
  EXPECT_GT(found, 2000) << "n " << n;
  EXPECT_GT(refused, 2000) << "n " << n;
  EXPECT_LT(points, refused / 100) << "n " << n;
}

TEST(FittingScale, AgreesWithPairwiseBoundsAtFixedSizes) {
  agree_on_random_cases<4>(4);
  agree_on_random_cases<6>(6);
  agree_on_random_cases<8>(8);
}

TEST(FittingScale, AgreesWithPairwiseBoundsAtDynamicSize) {
  for (int n : {5, 12, 16}) agree_on_random_cases<Eigen::Dynamic>(n);
}

// Whenever the kernel gives a scale, a shift exists that puts every motor in
// range: the promise the repair relies on.
TEST(FittingScale, AShiftFitsAtTheScaleFound) {
  std::mt19937_64 rng(99);
  const CommandRange r{0.0, 1.0};
  int checked = 0;
  for (int k = 0; k < 20000; ++k) {
    const Case c = random_case(rng, 8, k % 2 == 0, k % 4 == 1);
    for (const bool may_raise : {false, true}) {
      const double s = kernel<8>(c.base, c.part, c.thrust, r, may_raise);
      if (s < 0.0) continue;
      ASSERT_TRUE(shift_fits_at(c, s, r, may_raise)) << "case " << k << " s " << s;
      ++checked;
    }
  }
  EXPECT_GT(checked, 5000);
}

TEST(FittingScale, UniformBaseClosedFormMatchesTheReference) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const CommandRange r{0.0, 1.0};
  for (int k = 0; k < 20000; ++k) {
    const double thrust = (unit(rng) + 1.0) / 2.0;
    MotorVector base = MotorVector::Constant(6, thrust);
    MotorVector part(6);
    for (int i = 0; i < 6; ++i) part[i] = unit(rng);
    const MotorVector lift = MotorVector::Ones(6);
    for (const bool may_raise : {false, true}) {
      const double expected = pairwise_reference(base, part, lift, r, may_raise);
      const double got = detail::largest_fitting_scale_uniform_base(
          thrust, part.minCoeff(), part.maxCoeff(), r, may_raise);
      ASSERT_NEAR(got, expected, kScaleTolerance) << "case " << k;
    }
  }
}

}  // namespace
}  // namespace motormix
