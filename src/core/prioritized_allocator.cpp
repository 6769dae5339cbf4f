#include <motormix/prioritized_allocator.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace motormix {

PrioritizedAllocator::PrioritizedAllocator(const MixingMatrix& mixing, CommandRange range,
                                           Airmode airmode, double yaw_headroom)
    : MatrixAllocator(mixing, range),
      airmode_(airmode),
      yaw_headroom_(yaw_headroom),
      roll_(mixing.col(index(Axis::kRoll))),
      pitch_(mixing.col(index(Axis::kPitch))),
      yaw_(mixing.col(index(Axis::kYaw))),
      thrust_(mixing.col(index(Axis::kThrust))) {}

double PrioritizedAllocator::desaturation_gain(const MotorVector& u, const MotorVector& v,
                                               CommandRange range) const {
  // The smallest and largest gains that each bring one violating motor back
  // to its limit; their sum moves the worst violations symmetrically when
  // both limits are exceeded, and fully when only one is.
  double k_min = 0.0;
  double k_max = 0.0;
  for (Eigen::Index i = 0; i < u.size(); ++i) {
    if (std::abs(v[i]) < std::numeric_limits<float>::epsilon()) continue;
    double k = 0.0;
    if (u[i] < range.lower) {
      k = (range.lower - u[i]) / v[i];
    } else if (u[i] > range.upper) {
      k = (range.upper - u[i]) / v[i];
    } else {
      continue;
    }
    k_min = std::min(k_min, k);
    k_max = std::max(k_max, k);
  }
  return k_min + k_max;
}

const MotorVector& PrioritizedAllocator::column(Axis axis) const {
  switch (axis) {
    case Axis::kRoll:
      return roll_;
    case Axis::kPitch:
      return pitch_;
    case Axis::kYaw:
      return yaw_;
    case Axis::kThrust:
      break;
  }
  return thrust_;
}

void PrioritizedAllocator::desaturate(MotorVector& u, AxisVector& effective, Axis axis,
                                      CommandRange range, Direction direction) const {
  const MotorVector& v = column(axis);
  double gain = desaturation_gain(u, v, range);
  if (direction == Direction::kDecreaseOnly && gain > 0.0) return;
  u += gain * v;
  effective[index(axis)] += gain;
  // A second, half step balances what remains between the two limits.
  gain = 0.5 * desaturation_gain(u, v, range);
  u += gain * v;
  effective[index(axis)] += gain;
}

void PrioritizedAllocator::mix_yaw(double yaw, MotorVector& u, AxisVector& effective) const {
  u += yaw * yaw_;
  effective[index(Axis::kYaw)] = yaw;
  // Yaw gives way on its own axis (roll and pitch untouched), with some room
  // above the top so that full thrust still leaves yaw authority...
  CommandRange widened = range_;
  widened.upper += (range_.upper - range_.lower) * yaw_headroom_;
  desaturate(u, effective, Axis::kYaw, widened);
  // ...which thrust then pays for, only downward.
  desaturate(u, effective, Axis::kThrust, range_, Direction::kDecreaseOnly);
}

namespace {

// Bisection iterations for the largest scale that still fits: 2^-50 of full.
constexpr int kBisections = 50;

}  // namespace

void PrioritizedAllocator::repair(AxisVector& effective, MotorVector& u) const {
  const bool may_raise = airmode_ != Airmode::kOff;
  // Fits after the best allowed thrust shift? Returns the shift, or NaN.
  const auto fit = [&](const MotorVector& candidate) {
    ShiftInterval k = feasible_shifts(candidate, thrust_, range_);
    if (!may_raise) k.hi = std::min(k.hi, 0.0);
    if (k.empty()) return std::numeric_limits<double>::quiet_NaN();
    return k.smallest();
  };
  const auto mix_with = [&](double yaw_scale, double rp_scale) {
    MotorVector candidate = thrust_ * effective[index(Axis::kThrust)] +
                            yaw_ * (yaw_scale * effective[index(Axis::kYaw)]) +
                            roll_ * (rp_scale * effective[index(Axis::kRoll)]) +
                            pitch_ * (rp_scale * effective[index(Axis::kPitch)]);
    return candidate;
  };
  // Largest scale in [0, 1] of one part for which the mix fits (the spread is
  // convex in the scale, so the fitting scales form an interval from 0).
  const auto largest = [&](auto&& candidate_at) {
    if (!std::isnan(fit(candidate_at(1.0)))) return 1.0;
    if (std::isnan(fit(candidate_at(0.0)))) return 0.0;
    double ok = 0.0;
    double bad = 1.0;
    for (int i = 0; i < kBisections; ++i) {
      const double mid = 0.5 * (ok + bad);
      (std::isnan(fit(candidate_at(mid))) ? bad : ok) = mid;
    }
    return ok;
  };
  double yaw_scale = largest([&](double s) { return mix_with(s, 1.0); });
  double rp_scale = 1.0;
  if (yaw_scale == 0.0 && std::isnan(fit(mix_with(0.0, 1.0)))) {
    rp_scale = largest([&](double s) { return mix_with(0.0, s); });
  }
  u = mix_with(yaw_scale, rp_scale);
  const double shift = fit(u);
  if (!std::isnan(shift)) {
    u += shift * thrust_;
    effective[index(Axis::kThrust)] += shift;
  }
  effective[index(Axis::kYaw)] *= yaw_scale;
  effective[index(Axis::kRoll)] *= rp_scale;
  effective[index(Axis::kPitch)] *= rp_scale;
}

AllocationResult PrioritizedAllocator::allocate(const AxisVector& demand,
                                                MotorVector& commands) const {
  mix_linear(demand, commands);
  if (commands.minCoeff() >= range_.lower && commands.maxCoeff() <= range_.upper) {
    return finish(demand, commands);  // nothing saturates: nothing to prioritize
  }
  const double yaw = demand[index(Axis::kYaw)];
  AxisVector without_yaw = demand;
  without_yaw[index(Axis::kYaw)] = 0.0;
  AxisVector effective = without_yaw;
  switch (airmode_) {
    case Airmode::kOff:
      mix_linear(without_yaw, commands);
      desaturate(commands, effective, Axis::kThrust, range_, Direction::kDecreaseOnly);
      desaturate(commands, effective, Axis::kRoll, range_);
      desaturate(commands, effective, Axis::kPitch, range_);
      mix_yaw(yaw, commands, effective);
      break;
    case Airmode::kRollPitch:
      mix_linear(without_yaw, commands);
      desaturate(commands, effective, Axis::kThrust, range_);
      mix_yaw(yaw, commands, effective);
      break;
    case Airmode::kRollPitchYaw:
      effective = demand;
      mix_linear(demand, commands);
      desaturate(commands, effective, Axis::kThrust, range_);
      desaturate(commands, effective, Axis::kYaw, range_);
      break;
  }
  const bool out_of_range =
      commands.minCoeff() < range_.lower - 1e-12 || commands.maxCoeff() > range_.upper + 1e-12;
  if (out_of_range) repair(effective, commands);
  return finish(demand, commands);
}

}  // namespace motormix
