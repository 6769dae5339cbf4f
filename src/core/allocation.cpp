#include <motormix/allocation.hpp>

#include "fixed_size.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace motormix {

namespace {
// A command within this distance of a limit counts as sitting on it.
constexpr double kSaturationTolerance = 1e-9;
}  // namespace

AllocationResult describe_allocation(const EffectivenessMatrix& effectiveness,
                                     const AxisVector& target, const MotorVector& commands,
                                     CommandRange range, AxisMask controlled) {
  return detail::with_motor_count(commands.size(), [&](auto size) {
    constexpr int N = decltype(size)::value;
    const Eigen::Index n = commands.size();
    const detail::ConstMotorsView<N> u(commands.data(), n);
    const detail::ConstEffectivenessView<N> e(effectiveness.data(), kNumAxes, n);
    AllocationResult result;
    for (Eigen::Index i = 0; i < n; ++i) {
      result.saturated_upper |= static_cast<MotorMask>(u[i] >= range.upper - kSaturationTolerance)
                                << i;
      result.saturated_lower |= static_cast<MotorMask>(u[i] <= range.lower + kSaturationTolerance)
                                << i;
    }
    result.unallocated.noalias() = target - e * u;
    for (int a = 0; a < kNumAxes; ++a) {
      if (!((controlled >> a) & 1U)) result.unallocated[a] = 0.0;
      if (std::abs(result.unallocated[a]) > kDeliveredTolerance) {
        result.axis_limited |= static_cast<std::uint8_t>(1U << a);
      }
    }
    return result;
  });
}

ShiftInterval feasible_shifts(const MotorVector& u, const MotorVector& d, CommandRange range) {
  ShiftInterval k{-std::numeric_limits<double>::infinity(),
                  std::numeric_limits<double>::infinity()};
  for (Eigen::Index i = 0; i < u.size(); ++i) {
    if (d[i] <= 0.0) {
      if (u[i] < range.lower || u[i] > range.upper) return {1.0, -1.0};
      continue;
    }
    k.lo = std::max(k.lo, (range.lower - u[i]) / d[i]);
    k.hi = std::min(k.hi, (range.upper - u[i]) / d[i]);
  }
  return k;
}

MixingBasis::MixingBasis(const MixingMatrix& m)
    : mixing(m), effectiveness(effectiveness_of(m)), controlled(controlled_axes(m)) {}

MixingBasis::MixingBasis(const MixingMatrix& m, const EffectivenessMatrix& e, AxisMask c)
    : mixing(m), effectiveness(e), controlled(c) {}

MatrixAllocator::MatrixAllocator(const MixingBasis& basis, CommandRange range)
    : mixing_(basis.mixing),
      effectiveness_(basis.effectiveness),
      range_(range),
      controlled_(basis.controlled) {}

void MatrixAllocator::mix_linear(const AxisVector& demand, MotorVector& commands) const {
  const Eigen::Index n = mixing_.rows();
  commands.resize(n);
  detail::with_motor_count(n, [&](auto size) {
    constexpr int N = decltype(size)::value;
    detail::MotorsView<N>(commands.data(), n).noalias() =
        detail::ConstMixingView<N>(mixing_.data(), n, kNumAxes) * demand;
  });
}

AllocationResult MatrixAllocator::finish(const AxisVector& target, MotorVector& commands) const {
  for (Eigen::Index i = 0; i < commands.size(); ++i) {
    // NaN cannot come from finite inputs; if it ever did, the safe end.
    commands[i] = std::isnan(commands[i]) ? range_.lower
                                          : std::clamp(commands[i], range_.lower, range_.upper);
  }
  return describe_allocation(effectiveness_, target, commands, range_, controlled_);
}

}  // namespace motormix
