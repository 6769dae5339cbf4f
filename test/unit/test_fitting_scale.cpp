// The repair's one-dimensional problem (src/core/allocation/fitting_scale.hpp) against
// an independent reference: every pair of motors turned into a bound on s,
// the way it is derived on paper. The reference is O(n^2) and divides; the
// kernels step along the pieces of a convex excess. Random bases, parts and
// thrust columns (with motors the shift cannot move, and with equal lift),
// seeded; thrust that may not rise, rise by a quarter, or rise freely; 4, 6, 8 motors at fixed
// size and 5, 12, 16 at dynamic size.

#include <motormix/allocation/allocation.hpp>

#include "fitting_scale.hpp"
#include "shift_kernel.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace motormix {
namespace {

// Scales agree to this (they are tops of intervals bounded by ratios of
// numbers of order one).
constexpr double kScaleTolerance = 1e-9;
// How far the shift may rise: not at all (airmode off), by a quarter (a
// limited airmode), freely (airmode on).
constexpr double kNoCap = std::numeric_limits<double>::infinity();
constexpr double kRises[] = {0.0, 0.25, kNoCap};

// Largest s in [0, 1] for which some shift k (k <= rise)
// puts every motor of base + s part + k thrust in range; -1 if none.
double pairwise_reference(const MotorVector& base, const MotorVector& part,
                          const MotorVector& thrust, CommandRange r, double rise) {
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
    if (rise < kNoCap) keep(-rate_i, rise - low_i);
    for (Eigen::Index j = 0; j < n; ++j) {
      if (thrust[j] <= 0.0) continue;
      keep(part[j] / thrust[j] - rate_i, (r.upper - base[j]) / thrust[j] - low_i);
    }
  }
  return lo <= hi ? hi : -1.0;
}

template <int N>
double kernel(const MotorVector& base, const MotorVector& part, const MotorVector& thrust,
              CommandRange r, double rise) {
  const Eigen::Index n = base.size();
  const detail::LocalMotors<N> b = base;
  const detail::LocalMotors<N> p = part;
  const MotorVector lift = detail::positive_inverse(thrust);
  const detail::ConstMotorsView<N> view(lift.data(), n);
  return detail::largest_fitting_scale<N>(b, p, view, thrust.minCoeff() > 0.0, n, r, rise);
}

// Equal lift through the general kernel, as the repair calls it: the
// shared thrust offset folded into the base, a lift of 1 on every motor.
template <int N>
double equal_lift_kernel(double offset, const MotorVector& rest, const MotorVector& part,
                         CommandRange r, double rise) {
  const Eigen::Index n = rest.size();
  const detail::LocalMotors<N> b = (rest.array() + offset).matrix();
  const detail::LocalMotors<N> p = part;
  const detail::LocalMotors<N> lift = MotorVector::Ones(n);
  return detail::largest_fitting_scale<N>(b, p, lift, true, n, r, rise);
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

// Whether a shift (rising by `rise` at most) puts every motor of
// base + s part in range, within the rounding the repair allows.
bool shift_fits_at(const Case& c, double s, CommandRange r, double rise) {
  const MotorVector u = c.base + s * c.part;
  const MotorVector lift = detail::positive_inverse(c.thrust);
  ShiftInterval shift = detail::with_motor_count(u.size(), [&](auto size) {
    return detail::shifts_that_fit<decltype(size)::value>(u, lift, u.size(), r);
  });
  shift.hi = std::min(shift.hi, rise);
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
    for (const double rise : kRises) {
      const double expected = pairwise_reference(c.base, c.part, c.thrust, r, rise);
      const double got = kernel<N>(c.base, c.part, c.thrust, r, rise);
      if (expected < 0.0) {
        // No scale fits, or only a single point that the reference's
        // rounding loses: the kernel gives up too, or finds that point.
        if (got >= 0.0) {
          ASSERT_TRUE(shift_fits_at(c, got, r, rise)) << "n " << n << " case " << k;
          ++points;
        }
        ++refused;
        continue;
      }
      ++found;
      ASSERT_NEAR(got, expected, kScaleTolerance)
          << "n " << n << " case " << k << " raise " << rise;
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
    for (const double rise : kRises) {
      const double s = kernel<8>(c.base, c.part, c.thrust, r, rise);
      if (s < 0.0) continue;
      ASSERT_TRUE(shift_fits_at(c, s, r, rise)) << "case " << k << " s " << s;
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
    for (const double rise : kRises) {
      const double expected = pairwise_reference(base, part, lift, r, rise);
      const double got = detail::largest_fitting_scale_uniform_base(thrust, part.minCoeff(),
                                                                    part.maxCoeff(), r, rise);
      ASSERT_NEAR(got, expected, kScaleTolerance) << "case " << k;
    }
  }
}

// Equal lift and a part with one value per group of motors (yaw on rotors
// spinning two ways): the closed form against the pairwise reference.
TEST(FittingScale, TwoGroupClosedFormMatchesTheReference) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const CommandRange r{0.0, 1.0};
  int found = 0;
  for (int k = 0; k < 40000; ++k) {
    const int n = 4 + 2 * static_cast<int>(rng() % 3);
    const double offset = (unit(rng) + 1.0) / 2.0;
    // Small parts (a little yaw) amplify rounding where the scales narrow
    // to a point; bases that fill the range exactly make such points.
    const double size = k % 4 == 0 ? 0.01 : 1.0;
    const double part_a = size * unit(rng);
    const double part_b = k % 2 == 0 ? -part_a : size * unit(rng);
    MotorVector rest(n);
    MotorVector part(n);
    detail::GroupExtremes e{-1e300, 1e300, -1e300, 1e300};
    for (int i = 0; i < n; ++i) {
      rest[i] = 0.5 * unit(rng);
      const bool in_a = i % 2 == 0;
      part[i] = in_a ? part_a : part_b;
      if (in_a) {
        e.high_a = std::max(e.high_a, rest[i]);
        e.low_a = std::min(e.low_a, rest[i]);
      } else {
        e.high_b = std::max(e.high_b, rest[i]);
        e.low_b = std::min(e.low_b, rest[i]);
      }
    }
    if (k % 5 == 0) {
      // Group a spans the range exactly.
      rest[0] = 0.5;
      rest[2] = -0.5;
      e.high_a = std::max(e.high_a, 0.5);
      e.low_a = std::min(e.low_a, -0.5);
    }
    const MotorVector base = (rest.array() + offset).matrix();
    const MotorVector lift = MotorVector::Ones(n);
    for (const double rise : kRises) {
      const double expected = pairwise_reference(base, part, lift, r, rise);
      const double got =
          detail::largest_fitting_scale_two_groups(offset, e, part_a, part_b, r, rise);
      // The stepping kernel on the same motors finds the same scale, single
      // points included (the repair uses either, by geometry).
      const double stepped = equal_lift_kernel<Eigen::Dynamic>(offset, rest, part, r, rise);
      ASSERT_EQ(got >= 0.0, stepped >= 0.0)
          << "case " << k << " two groups " << got << " stepped " << stepped;
      if (got >= 0.0) {
        ASSERT_NEAR(got, stepped, kScaleTolerance) << "case " << k;
      }
      if (expected < 0.0 && got >= 0.0) {
        // A single fitting point the reference's rounding loses.
        Case c{base, part, lift};
        ASSERT_TRUE(shift_fits_at(c, got, r, rise)) << "case " << k;
        continue;
      }
      ASSERT_NEAR(got, expected, kScaleTolerance)
          << "case " << k << " raise " << rise << " offset " << offset << " parts " << part_a << " "
          << part_b << " rest " << rest.transpose();
      found += expected >= 0.0;
    }
  }
  EXPECT_GT(found, 5000);
}

// Scales that narrow to a single point s*: group a spans the whole range,
// its lowest motor reaches the bottom at s* from below, and the cross bound
// closes at s* from above (thrust may not rise). A little yaw (small parts)
// amplifies the rounding of such points; both kernels must still find s*.
TEST(FittingScale, SinglePointScalesAreFound) {
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const CommandRange r{0.0, 1.0};
  for (int k = 0; k < 5000; ++k) {
    const double offset = 0.3 + 0.4 * unit(rng);
    const double alpha = 0.001 + 0.05 * unit(rng);
    const double point = 0.1 + 0.8 * unit(rng);
    const double low_b = alpha * point - offset;
    const double high_a = low_b + 1.0 - 2.0 * alpha * point;
    const double low_a = -offset - point * alpha;
    MotorVector rest(4);
    rest << high_a, low_b, low_a, low_b;  // a, b, a, b
    MotorVector part(4);
    part << alpha, -alpha, alpha, -alpha;
    const detail::GroupExtremes e{high_a, low_a, low_b, low_b};
    const double closed =
        detail::largest_fitting_scale_two_groups(offset, e, alpha, -alpha, r, 0.0);
    const double stepped = equal_lift_kernel<4>(offset, rest, part, r, false);
    ASSERT_NEAR(closed, point, kScaleTolerance) << "case " << k;
    ASSERT_NEAR(stepped, point, kScaleTolerance) << "case " << k;
  }
}

// The public feasible_shifts (allocation.hpp) against its definition, on
// seeded random mixes with motors the direction cannot move (d <= 0) among
// them: at both ends of a non-empty interval every motor is in range, a
// step past either end takes a movable motor out, and the interval is
// empty exactly when an unmovable motor is out of range or the ends cross.
TEST(FeasibleShifts, MatchesItsDefinition) {
  constexpr double kInRange = 1e-12;  // rounding of u + k d at an end
  constexpr double kStep = 1e-6;      // a step past an end, far above that rounding
  const CommandRange r{0.1, 0.9};
  const auto in_range = [&](double v) {
    return v >= r.lower - kInRange && v <= r.upper + kInRange;
  };
  std::mt19937 rng(2026);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int empty = 0;
  int stuck = 0;
  for (int k = 0; k < 20000; ++k) {
    const int n = 1 + k % 8;
    MotorVector u(n);
    MotorVector d(n);
    bool unmovable_out = false;
    for (int i = 0; i < n; ++i) {
      u[i] = -0.5 + 2.0 * unit(rng);
      const double pick = unit(rng);
      d[i] = pick < 0.15 ? 0.0 : (pick < 0.25 ? -unit(rng) : 0.05 + unit(rng));
      if (d[i] <= 0.0 && !(u[i] >= r.lower && u[i] <= r.upper)) unmovable_out = true;
    }
    const ShiftInterval s = feasible_shifts(u, d, r);
    // As documented, a motor with d <= 0 is one the shift does not move.
    const MotorVector moved = d.cwiseMax(0.0);
    const auto fits_after = [&](double shift) {
      return (u + shift * moved).array().unaryExpr(in_range).all();
    };
    if (unmovable_out) {
      ASSERT_TRUE(s.empty()) << "case " << k;
      ++stuck;
      continue;
    }
    // Any finite shift works when no motor moves: the bounds stay infinite.
    if ((d.array() <= 0.0).all()) {
      ASSERT_FALSE(s.empty());
      ASSERT_TRUE(std::isinf(s.lo) && std::isinf(s.hi)) << "case " << k;
      continue;
    }
    if (s.empty()) {
      // The ends crossed: some pair of movable motors cannot both fit. At
      // the midpoint of the crossed ends at least one motor is out.
      const double mid = 0.5 * (s.lo + s.hi);
      ASSERT_FALSE(fits_after(mid)) << "case " << k;
      ++empty;
      continue;
    }
    for (const double end : {s.lo, s.hi}) {
      ASSERT_TRUE(fits_after(end)) << "case " << k;
    }
    ASSERT_FALSE(fits_after(s.lo - kStep)) << "case " << k;
    ASSERT_FALSE(fits_after(s.hi + kStep)) << "case " << k;
  }
  // The seeded draw reaches every branch.
  EXPECT_GT(stuck, 100);
  EXPECT_GT(empty, 100);
}

}  // namespace
}  // namespace motormix
