#include <motormix/optimal_allocator.hpp>

#include <Eigen/QR>

#include <algorithm>
#include <cmath>

namespace motormix {

namespace {

constexpr int kRowsMax = kNumAxes + kMaxMotors;
using StackedMatrix =
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, kRowsMax, kMaxMotors>;
using StackedVector = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, kRowsMax, 1>;

// Attitude error weight against the tie-break term.
constexpr double kGamma = 1e6;
// Multipliers above this count as non-negative (optimality test).
constexpr double kMultiplierTolerance = 1e-12;

enum : signed char { kFree = 0, kAtLower = -1, kAtUpper = 1 };

}  // namespace

OptimalAllocator::OptimalAllocator(const MixingBasis& basis, CommandRange range,
                                   OptimalSettings settings)
    : MatrixAllocator(basis, range), settings_(settings) {}

double weighted_error(const EffectivenessMatrix& effectiveness, const AxisVector& weights,
                      const AxisVector& demand, const MotorVector& commands) {
  const AxisVector e = weights.cwiseProduct(effectiveness * commands - demand);
  return e.squaredNorm();
}

AllocationResult OptimalAllocator::allocate(const AxisVector& demand, MotorVector& commands) const {
  const Eigen::Index n = mixing_.rows();
  const double sqrt_gamma = std::sqrt(kGamma);

  // Stacked least squares: A u ~ b with A = [sqrt(g) W E; I], b = [sqrt(g) W d; u_p].
  MotorVector preferred = mixing_ * demand;
  for (Eigen::Index i = 0; i < n; ++i) {
    preferred[i] = std::clamp(preferred[i], range_.lower, range_.upper);
  }
  StackedMatrix a(kNumAxes + n, n);
  StackedVector b(kNumAxes + n);
  for (int r = 0; r < kNumAxes; ++r) {
    a.row(r) = sqrt_gamma * settings_.weights[r] * effectiveness_.row(r);
    b[r] = sqrt_gamma * settings_.weights[r] * demand[r];
  }
  a.bottomRows(n).setIdentity();
  b.tail(n) = preferred;

  // Start feasible: the clipped linear mix, with motors on a limit active.
  commands = preferred;
  Eigen::Matrix<signed char, Eigen::Dynamic, 1, Eigen::ColMajor, kMaxMotors, 1> active(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    active[i] = commands[i] <= range_.lower   ? kAtLower
                : commands[i] >= range_.upper ? kAtUpper
                                              : kFree;
  }
  StackedVector residual = b - a * commands;

  StackedMatrix a_free;
  MotorVector step_free;
  MotorVector step(n);
  Eigen::Matrix<int, Eigen::Dynamic, 1, Eigen::ColMajor, kMaxMotors, 1> free_index(n);
  Eigen::ColPivHouseholderQR<StackedMatrix> qr(kNumAxes + n, n);

  for (int iteration = 0; iteration < settings_.max_iterations; ++iteration) {
    Eigen::Index nf = 0;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (active[i] == kFree) free_index[nf++] = static_cast<int>(i);
    }
    step.setZero();
    if (nf > 0) {
      a_free.resize(kNumAxes + n, nf);
      for (Eigen::Index j = 0; j < nf; ++j) a_free.col(j) = a.col(free_index[j]);
      qr.compute(a_free);
      step_free = qr.solve(residual);
      for (Eigen::Index j = 0; j < nf; ++j) step[free_index[j]] = step_free[j];
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
    residual -= alpha * (a * step);
    if (blocking >= 0) {
      active[blocking] = step[blocking] > 0.0 ? kAtUpper : kAtLower;
      commands[blocking] = active[blocking] == kAtUpper ? range_.upper : range_.lower;
      continue;
    }
    // Full step taken: optimal on this working set. Release the constraint
    // whose multiplier says the error would drop by leaving it, if any.
    const MotorVector gradient = a.transpose() * residual;  // descent direction per motor
    Eigen::Index release = -1;
    double most_negative = -kMultiplierTolerance;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (active[i] == kFree) continue;
      // At the upper limit the error would drop by moving down: gradient < 0.
      const double multiplier = active[i] == kAtUpper ? gradient[i] : -gradient[i];
      if (multiplier < most_negative) most_negative = multiplier, release = i;
    }
    if (release < 0) break;
    active[release] = kFree;
  }
  return finish(demand, commands);
}

}  // namespace motormix
