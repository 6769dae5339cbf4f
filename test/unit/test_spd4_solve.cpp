// The unrolled 4 x 4 solve of `optimal`'s Newton step (src/core/allocation/spd4_solve.hpp)
// against Eigen's pivoting LDLT, on the systems the solver builds: B_f B_f^T
// + I / gamma for random effectiveness columns, with 0 to 8 free motors (so
// from the identity over gamma, through rank-deficient sums, to full rank),
// and on matrices that are not positive definite, which it must refuse.

#include "spd4_solve.hpp"

#include <Eigen/Cholesky>

#include <gtest/gtest.h>

#include <random>

namespace motormix {
namespace {

// The solver's gamma: the smallest eigenvalue is 1 / gamma, the condition
// number up to about 1e7, so relative agreement to 1e-6 of the solution's
// size is what double precision allows both factorizations.
constexpr double kGamma = 1e6;
constexpr double kRelativeTolerance = 1e-6;

TEST(Spd4Solve, AgreesWithPivotingLdltOnTheNewtonStepsSystems) {
  std::mt19937 rng(1204);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  int solved = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const int free_motors = trial % 9;
    Eigen::Matrix4d a = Eigen::Matrix4d::Identity() / kGamma;
    for (int j = 0; j < free_motors; ++j) {
      Eigen::Vector4d b;
      b << unit(rng), unit(rng), 0.2 * unit(rng), 0.5 * (unit(rng) + 1.0);
      a.noalias() += b * b.transpose();
    }
    Eigen::Vector4d rhs;
    rhs << unit(rng), unit(rng), unit(rng), unit(rng);
    Eigen::Vector4d x;
    ASSERT_TRUE(detail::solve_spd4(a, rhs, x)) << "trial " << trial << "\n" << a;
    const Eigen::Vector4d reference = a.ldlt().solve(rhs);
    ASSERT_LE((x - reference).norm(), kRelativeTolerance * reference.norm())
        << "trial " << trial << " free motors " << free_motors;
    ++solved;
  }
  EXPECT_EQ(solved, 20000);
}

TEST(Spd4Solve, ReadsOnlyTheLowerTriangle) {
  Eigen::Matrix4d a;
  a << 4, 0, 0, 0,     //
      1, 3, 0, 0,      //
      0.5, 0.2, 2, 0,  //
      0.1, 0.3, 0.4, 1;
  const Eigen::Matrix4d full = a.selfadjointView<Eigen::Lower>();
  const Eigen::Vector4d rhs(1, -2, 3, -4);
  Eigen::Vector4d x;
  ASSERT_TRUE(detail::solve_spd4(a, rhs, x));
  EXPECT_LE((full * x - rhs).norm(), 1e-12);
}

TEST(Spd4Solve, RefusesWhatIsNotPositiveDefinite) {
  const Eigen::Vector4d rhs(1, 1, 1, 1);
  Eigen::Vector4d x;
  Eigen::Matrix4d indefinite = Eigen::Matrix4d::Identity();
  indefinite(2, 2) = -1.0;
  EXPECT_FALSE(detail::solve_spd4(indefinite, rhs, x));
  EXPECT_FALSE(detail::solve_spd4(Eigen::Matrix4d::Zero(), rhs, x));
  Eigen::Matrix4d singular = Eigen::Matrix4d::Ones();  // rank one
  EXPECT_FALSE(detail::solve_spd4(singular, rhs, x));
  Eigen::Matrix4d with_nan = Eigen::Matrix4d::Identity();
  with_nan(3, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(detail::solve_spd4(with_nan, rhs, x));
  Eigen::Matrix4d with_inf = Eigen::Matrix4d::Identity();
  with_inf(3, 3) = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(detail::solve_spd4(with_inf, rhs, x));
}

}  // namespace
}  // namespace motormix
