#include <motormix/allocation/optimal_allocator.hpp>

#include "fixed_size.hpp"
#include "report_kernel.hpp"
#include "spd4_solve.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>

namespace motormix {

namespace {

// Attitude error weight against the tie-break term.
constexpr double kGamma = 1e6;
// Multipliers above this count as non-negative (optimality test).
constexpr double kMultiplierTolerance = 1e-12;

enum : signed char { kFree = 0, kAtLower = -1, kAtUpper = 1 };

}  // namespace

OptimalAllocator::OptimalAllocator(const MixingBasis& basis, CommandRange range,
                                   OptimalSettings settings)
    : MatrixAllocator(basis, range), settings_(settings) {
  weighted_ = effectiveness_;
  for (int r = 0; r < kNumAxes; ++r) weighted_.row(r) *= settings_.weights[r];
}

double weighted_error(const EffectivenessMatrix& effectiveness, const AxisVector& weights,
                      const AxisVector& demand, const MotorVector& commands) {
  const AxisVector e = weights.cwiseProduct(effectiveness * commands - demand);
  return e.squaredNorm();
}

// The active-set iteration at N motors (fixed where the count has its own
// instantiation, see fixed_size.hpp): every per-motor loop has a constant
// bound the compiler unrolls, and the step is one product masked to the free
// motors instead of a loop over a list of them. The dual skips held motors
// by a branch: at a fixed count, multiplying their columns by zero instead
// was slower (see docs/benchmark_history.md). Each iteration is a chain of dependent steps
// (the dual's factorization, the step, the ratio test), so its length, not
// the arithmetic, sets the time.
template <int N>
AllocationResult OptimalAllocator::solve(const AxisVector& demand, double* out,
                                         Eigen::Index n) const {
  using Motors = detail::LocalMotors<N>;
  constexpr int kCapacity = N == Eigen::Dynamic ? kMaxMotors : N;
  const Eigen::Index motors = detail::count<N>(n);
  const double lower = range_.lower;
  const double upper = range_.upper;
  const detail::ConstEffectivenessView<N> b(weighted_.data(), kNumAxes, n);  // B = W E
  // Preferred commands: the plain linear mix clipped to the limits.
  Motors preferred(n);
  preferred.noalias() =
      detail::ConstMixingColumnsView<N>(mixing_by_column_.data(), n, kNumAxes) * demand;
  for (Eigen::Index i = 0; i < motors; ++i) preferred[i] = std::clamp(preferred[i], lower, upper);
  // Start feasible: the clipped linear mix, with motors on a limit active.
  Motors u = preferred;
  Eigen::Matrix<signed char, N, 1, Eigen::ColMajor, kCapacity, 1> side(n);
  for (Eigen::Index i = 0; i < motors; ++i) {
    side[i] = u[i] <= lower ? kAtLower : u[i] >= upper ? kAtUpper : kFree;
  }
  // The cost is gamma |e|^2 + |q|^2 with e = W (d - E u) and q = u_p - u.
  // Both residuals are kept up to date as u moves.
  AxisVector e = settings_.weights.cwiseProduct(demand) - b * u;
  Motors q = Motors::Zero(n);
  Motors step(n);
  Motors g(n);  // gamma B^T e + q: the descent direction of the cost, per motor
  int iteration = 0;
  for (; iteration < settings_.max_iterations; ++iteration) {
    // Newton step on the free motors: (I + gamma B_f^T B_f) s_f = gamma B_f^T e + q_f,
    // solved through its 4 x 4 dual (Woodbury) in the form that never
    // multiplies by gamma:
    //   s_f = q_f + B_f^T z,   (B_f B_f^T + I / gamma) z = e - B_f q_f,
    // so an iteration costs the same small solve for any motor count.
    Eigen::Matrix4d dual = Eigen::Matrix4d::Identity() / kGamma;
    AxisVector rhs = e;
    for (Eigen::Index i = 0; i < motors; ++i) {
      if (side[i] != kFree) continue;
      const auto column = b.col(i);
      dual.noalias() += column * column.transpose();
      rhs -= column * q[i];
    }
    AxisVector z;
    // Positive definite by construction; should rounding ever say
    // otherwise, the pivoting factorization.
    if (!detail::solve_spd4(dual, rhs, z)) z = dual.ldlt().solve(rhs);
    step.noalias() = b.transpose() * z;
    for (Eigen::Index i = 0; i < motors; ++i) step[i] = side[i] == kFree ? step[i] + q[i] : 0.0;
    // Largest fraction of the step that keeps every free motor in range (a
    // held motor's step is zero: it never blocks).
    double alpha = 1.0;
    Eigen::Index blocking = -1;
    for (Eigen::Index i = 0; i < motors; ++i) {
      const double target = u[i] + step[i];
      const bool over = target > upper && step[i] > 0.0;
      const bool under = target < lower && step[i] < 0.0;
      if (over || under) {
        const double f = ((over ? upper : lower) - u[i]) / step[i];
        if (f < alpha) alpha = f, blocking = i;
      }
    }
    u += alpha * step;
    e.noalias() -= alpha * (b * step);
    q -= alpha * step;
    if (blocking >= 0) {
      side[blocking] = step[blocking] > 0.0 ? kAtUpper : kAtLower;
      const double limit = side[blocking] == kAtUpper ? upper : lower;
      q[blocking] += u[blocking] - limit;
      e += b.col(blocking) * (u[blocking] - limit);
      u[blocking] = limit;
      continue;
    }
    // Full step taken: optimal on this working set. Release the constraint
    // whose multiplier says the error would drop by leaving it, if any.
    g.noalias() = b.transpose() * e;
    g = kGamma * g + q;  // descent direction per motor
    Eigen::Index release = -1;
    double most_negative = -kMultiplierTolerance;
    for (Eigen::Index i = 0; i < motors; ++i) {
      // At the upper limit the error would drop by moving down: g < 0. A
      // free motor has no multiplier.
      const double multiplier = side[i] == kAtUpper ? g[i] : side[i] == kAtLower ? -g[i] : 0.0;
      if (multiplier < most_negative) most_negative = multiplier, release = i;
    }
    if (release < 0) break;
    side[release] = kFree;
  }
  // Rounding aside the iterate is in range; a NaN (which finite inputs
  // cannot produce) goes to the safe end.
  detail::clamp_into_range<N>(u, cycle_constants_);
  detail::MotorsView<N>(out, n) = u;
  AllocationResult result =
      detail::describe_fixed<N>(effectiveness_, demand, u.data(), n, cycle_constants_);
  result.iterations = static_cast<std::uint16_t>(std::min(iteration + 1, settings_.max_iterations));
  return result;
}

AllocationResult OptimalAllocator::allocate(const AxisVector& demand, MotorVector& commands) const {
  const Eigen::Index n = mixing_.rows();
  commands.resize(n);
  return detail::with_motor_count(
      n,
      [](auto size, const OptimalAllocator& self, const AxisVector& target, double* out,
         Eigen::Index motors) { return self.solve<decltype(size)::value>(target, out, motors); },
      *this, demand, commands.data(), n);
}

}  // namespace motormix
