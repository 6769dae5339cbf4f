#include <motormix/optimal_allocator.hpp>

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

AllocationResult OptimalAllocator::allocate(const AxisVector& demand, MotorVector& commands) const {
  const Eigen::Index n = mixing_.rows();
  // Preferred commands: the plain linear mix clipped to the limits.
  mix_linear(demand, commands);
  MotorVector preferred(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    preferred[i] = std::clamp(commands[i], range_.lower, range_.upper);
  }
  // Start feasible: the clipped linear mix, with motors on a limit active.
  commands = preferred;
  Eigen::Matrix<signed char, Eigen::Dynamic, 1, Eigen::ColMajor, kMaxMotors, 1> active(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    active[i] = commands[i] <= range_.lower   ? kAtLower
                : commands[i] >= range_.upper ? kAtUpper
                                              : kFree;
  }
  // The cost is gamma |e|^2 + |q|^2 with e = W (d - E u) and q = u_p - u.
  // Both residuals are kept up to date as u moves.
  AxisVector e = settings_.weights.cwiseProduct(demand) - weighted_ * commands;
  MotorVector q = MotorVector::Zero(n);

  Eigen::Matrix<int, Eigen::Dynamic, 1, Eigen::ColMajor, kMaxMotors, 1> free_index(n);
  MotorVector step(n);
  MotorVector g(n);  // gamma B^T e + q: the descent direction of the cost, per motor
  int iteration = 0;
  for (; iteration < settings_.max_iterations; ++iteration) {
    // Newton step on the free motors: (I + gamma B_f^T B_f) s_f = gamma B_f^T e + q_f
    // (B = W E), solved through its 4 x 4 dual (Woodbury) in the form that
    // never multiplies by gamma:
    //   s_f = q_f + B_f^T z,   (B_f B_f^T + I / gamma) z = e - B_f q_f,
    // so an iteration costs the same small solve for any motor count.
    Eigen::Matrix4d dual = Eigen::Matrix4d::Identity() / kGamma;
    AxisVector rhs = e;
    Eigen::Index nf = 0;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (active[i] != kFree) continue;
      free_index[nf++] = static_cast<int>(i);
      const auto b = weighted_.col(i);
      dual.noalias() += b * b.transpose();
      rhs -= b * q[i];
    }
    step.setZero();
    if (nf > 0) {
      AxisVector z;
      // Positive definite by construction; should rounding ever say
      // otherwise, the pivoting factorization.
      if (!detail::solve_spd4(dual, rhs, z)) z = dual.ldlt().solve(rhs);
      for (Eigen::Index j = 0; j < nf; ++j) {
        const Eigen::Index i = free_index[j];
        step[i] = q[i] + weighted_.col(i).dot(z);
      }
    }
    // Largest fraction of the step that keeps every free motor in range.
    double alpha = 1.0;
    Eigen::Index blocking = -1;
    for (Eigen::Index j = 0; j < nf; ++j) {
      const Eigen::Index i = free_index[j];
      const double target = commands[i] + step[i];
      if (target > range_.upper && step[i] > 0.0) {
        const double f = (range_.upper - commands[i]) / step[i];
        if (f < alpha) alpha = f, blocking = i;
      } else if (target < range_.lower && step[i] < 0.0) {
        const double f = (range_.lower - commands[i]) / step[i];
        if (f < alpha) alpha = f, blocking = i;
      }
    }
    commands += alpha * step;
    e.noalias() -= alpha * (weighted_ * step);
    q -= alpha * step;
    if (blocking >= 0) {
      active[blocking] = step[blocking] > 0.0 ? kAtUpper : kAtLower;
      const double limit = active[blocking] == kAtUpper ? range_.upper : range_.lower;
      q[blocking] += commands[blocking] - limit;
      e += weighted_.col(blocking) * (commands[blocking] - limit);
      commands[blocking] = limit;
      continue;
    }
    // Full step taken: optimal on this working set. Release the constraint
    // whose multiplier says the error would drop by leaving it, if any.
    g.noalias() = kGamma * (weighted_.transpose() * e);
    g += q;  // descent direction per motor
    Eigen::Index release = -1;
    double most_negative = -kMultiplierTolerance;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (active[i] == kFree) continue;
      // At the upper limit the error would drop by moving down: g < 0.
      const double multiplier = active[i] == kAtUpper ? g[i] : -g[i];
      if (multiplier < most_negative) most_negative = multiplier, release = i;
    }
    if (release < 0) break;
    active[release] = kFree;
  }
  AllocationResult result = finish(demand, commands);
  result.iterations = static_cast<std::uint16_t>(std::min(iteration + 1, settings_.max_iterations));
  return result;
}

}  // namespace motormix
