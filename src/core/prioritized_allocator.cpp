#include <motormix/prioritized_allocator.hpp>

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

void PrioritizedAllocator::desaturate(MotorVector& u, const MotorVector& v, CommandRange range,
                                      Direction direction) const {
  double gain = desaturation_gain(u, v, range);
  if (direction == Direction::kDecreaseOnly && gain > 0.0) return;
  u += gain * v;
  // A second, half step balances what remains between the two limits.
  gain = 0.5 * desaturation_gain(u, v, range);
  u += gain * v;
}

void PrioritizedAllocator::mix_yaw(double yaw, MotorVector& u) const {
  u += yaw * yaw_;
  // Yaw gives way on its own axis (roll and pitch untouched), with some room
  // above the top so that full thrust still leaves yaw authority...
  CommandRange widened = range_;
  widened.upper += (range_.upper - range_.lower) * yaw_headroom_;
  desaturate(u, yaw_, widened);
  // ...which thrust then pays for, only downward.
  desaturate(u, thrust_, range_, Direction::kDecreaseOnly);
}

AllocationResult PrioritizedAllocator::allocate(const AxisVector& demand,
                                                MotorVector& commands) const {
  const double yaw = demand[index(Axis::kYaw)];
  AxisVector without_yaw = demand;
  without_yaw[index(Axis::kYaw)] = 0.0;
  switch (airmode_) {
    case Airmode::kOff:
      mix_linear(without_yaw, commands);
      desaturate(commands, thrust_, range_, Direction::kDecreaseOnly);
      desaturate(commands, roll_, range_);
      desaturate(commands, pitch_, range_);
      mix_yaw(yaw, commands);
      break;
    case Airmode::kRollPitch:
      mix_linear(without_yaw, commands);
      desaturate(commands, thrust_, range_);
      // Only when thrust alone cannot make room (spread wider than the
      // range) do roll and pitch give way, rather than being clipped.
      desaturate(commands, roll_, range_);
      desaturate(commands, pitch_, range_);
      mix_yaw(yaw, commands);
      break;
    case Airmode::kRollPitchYaw:
      mix_linear(demand, commands);
      desaturate(commands, thrust_, range_);
      desaturate(commands, yaw_, range_);
      desaturate(commands, roll_, range_);
      desaturate(commands, pitch_, range_);
      break;
  }
  return finish(demand, commands);
}

}  // namespace motormix
