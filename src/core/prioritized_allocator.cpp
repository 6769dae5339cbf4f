#include <motormix/prioritized_allocator.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace motormix {

PrioritizedAllocator::PrioritizedAllocator(const MixingBasis& basis, CommandRange range,
                                           Airmode airmode, double yaw_headroom)
    : MatrixAllocator(basis, range),
      airmode_(airmode),
      yaw_headroom_(yaw_headroom),
      roll_(mixing_.col(index(Axis::kRoll))),
      pitch_(mixing_.col(index(Axis::kPitch))),
      yaw_(mixing_.col(index(Axis::kYaw))),
      thrust_(mixing_.col(index(Axis::kThrust))) {}

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

double PrioritizedAllocator::largest_fitting_scale(const MotorVector& base, const MotorVector& part,
                                                   bool may_raise) const {
  // Motor i stays in range after a thrust shift k when
  //   lower <= base_i + s part_i + k thrust_i <= upper.
  // Motors with thrust_i > 0 give bounds on k that are linear in s:
  //   L_i(s) = (lower - base_i - s part_i) / thrust_i <= k <= U_i(s) = (upper - ...) / thrust_i.
  // A k exists iff every L_i(s) <= every U_j(s) (and L_i(s) <= 0 when thrust
  // may not rise); motors that thrust does not move must fit on their own.
  // Each condition is a half-line a s <= c, so the scales that fit form an
  // interval, and its top is the answer: exact, with no search.
  double lo = 0.0;
  double hi = 1.0;
  const auto keep = [&](double a, double c) {  // a s <= c
    if (a > 0.0) {
      hi = std::min(hi, c / a);
    } else if (a < 0.0) {
      lo = std::max(lo, c / a);
    } else if (c < 0.0) {
      hi = -1.0;  // no scale at all
    }
  };
  const Eigen::Index n = base.size();
  std::array<double, kMaxMotors> rate{};     // part_i / thrust_i
  std::array<double, kMaxMotors> low_at0{};  // L_i(0)
  std::array<double, kMaxMotors> up_at0{};   // U_i(0)
  int moving = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (thrust_[i] <= 0.0) {
      keep(part[i], range_.upper - base[i]);
      keep(-part[i], base[i] - range_.lower);
      continue;
    }
    const double inv = 1.0 / thrust_[i];
    rate[static_cast<std::size_t>(moving)] = part[i] * inv;
    low_at0[static_cast<std::size_t>(moving)] = (range_.lower - base[i]) * inv;
    up_at0[static_cast<std::size_t>(moving)] = (range_.upper - base[i]) * inv;
    ++moving;
  }
  for (int i = 0; i < moving; ++i) {
    const auto a = static_cast<std::size_t>(i);
    if (!may_raise) keep(-rate[a], -low_at0[a]);  // L_i(s) <= 0
    for (int j = 0; j < moving; ++j) {            // L_i(s) <= U_j(s)
      const auto b = static_cast<std::size_t>(j);
      keep(rate[b] - rate[a], up_at0[b] - low_at0[a]);
    }
  }
  return lo <= hi ? hi : -1.0;
}

void PrioritizedAllocator::repair(AxisVector& effective, MotorVector& u) const {
  const bool may_raise = airmode_ != Airmode::kOff;
  const double roll = effective[index(Axis::kRoll)];
  const double pitch = effective[index(Axis::kPitch)];
  const double yaw = effective[index(Axis::kYaw)];
  const MotorVector thrust_part = thrust_ * effective[index(Axis::kThrust)];
  const MotorVector rp_part = roll_ * roll + pitch_ * pitch;
  // Yaw gives way first: the largest share of it that fits with all of roll
  // and pitch. Only when none fits do roll and pitch give way, without yaw.
  double yaw_scale = largest_fitting_scale(thrust_part + rp_part, yaw_ * yaw, may_raise);
  double rp_scale = 1.0;
  if (yaw_scale < 0.0) {
    yaw_scale = 0.0;
    rp_scale = std::max(0.0, largest_fitting_scale(thrust_part, rp_part, may_raise));
  }
  u = thrust_part + yaw_scale * (yaw_ * yaw) + rp_scale * rp_part;
  ShiftInterval k = feasible_shifts(u, thrust_, range_);
  if (!may_raise) k.hi = std::min(k.hi, 0.0);
  // At the largest scale some motor sits exactly on its limit: rounding may
  // leave the interval a few ulps wide of empty.
  constexpr double kRounding = 1e-12;
  if (k.empty() && k.lo - k.hi < kRounding) k.lo = k.hi = 0.5 * (k.lo + k.hi);
  if (!k.empty()) {
    const double shift = k.smallest();
    u += shift * thrust_;
    effective[index(Axis::kThrust)] += shift;
  }
  effective[index(Axis::kYaw)] *= yaw_scale;
  effective[index(Axis::kRoll)] *= rp_scale;
  effective[index(Axis::kPitch)] *= rp_scale;
}

bool PrioritizedAllocator::closer_in_priority_order(const AxisVector& error_a,
                                                    const AxisVector& error_b, double tolerance) {
  const std::array<std::pair<double, double>, 3> in_order = {
      std::pair{std::hypot(error_a[index(Axis::kRoll)], error_a[index(Axis::kPitch)]),
                std::hypot(error_b[index(Axis::kRoll)], error_b[index(Axis::kPitch)])},
      std::pair{std::abs(error_a[index(Axis::kThrust)]), std::abs(error_b[index(Axis::kThrust)])},
      std::pair{std::abs(error_a[index(Axis::kYaw)]), std::abs(error_b[index(Axis::kYaw)])}};
  for (const auto& [x, y] : in_order) {
    if (x < y - tolerance) return true;
    if (x > y + tolerance) return false;
  }
  return false;  // a tie keeps the repair
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
  if (out_of_range) {
    // Two ways to bring the sequence's result into range: the repair (scale
    // yaw, then roll and pitch, along their demanded directions, with the
    // best thrust shift), or clipping each motor as sequential desaturation
    // does elsewhere. Clipping can change the direction of the delivered
    // torque yet land closer to the demand. Keep whichever delivers the
    // demand better in priority order: roll and pitch, then thrust, then yaw.
    MotorVector clipped = commands.cwiseMax(range_.lower).cwiseMin(range_.upper);
    repair(effective, commands);
    const AllocationResult repaired = finish(demand, commands);
    const AllocationResult clip = finish(demand, clipped);
    if (closer_in_priority_order(clip.unallocated, repaired.unallocated)) {
      commands = clipped;
      return clip;
    }
    return repaired;
  }
  return finish(demand, commands);
}

}  // namespace motormix
