#include <motormix/allocation/allocation.hpp>

#include "shift_kernel.hpp"

#include "fixed_size.hpp"
#include "report_kernel.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace motormix {

AllocationResult describe_allocation(const EffectivenessMatrix& effectiveness,
                                     const AxisVector& target, const MotorVector& commands,
                                     CommandRange range, AxisMask controlled) {
  return describe_allocation(effectiveness, target, commands, CycleConstants(range, controlled));
}

AllocationResult describe_allocation(const EffectivenessMatrix& effectiveness,
                                     const AxisVector& target, const MotorVector& commands,
                                     const CycleConstants& limits) {
  return detail::with_motor_count(commands.size(), [&](auto size) {
    return detail::describe_fixed<decltype(size)::value>(effectiveness, target, commands.data(),
                                                         commands.size(), limits);
  });
}

ShiftInterval feasible_shifts(const MotorVector& u, const MotorVector& d, CommandRange range) {
  return detail::with_motor_count(u.size(), [&](auto size) {
    constexpr int kN = decltype(size)::value;
    detail::LocalMotors<kN> inverse(u.size());
    detail::direction_inverse(d, /*positive_only=*/true, 0.0, inverse);
    return detail::shifts_that_fit<kN>(u, inverse, u.size(), range);
  });
}

CycleConstants::CycleConstants(CommandRange range, AxisMask controlled)
    : lower{range.lower, range.lower},
      upper{range.upper, range.upper},
      at_upper{range.upper - detail::kSaturationTolerance,
               range.upper - detail::kSaturationTolerance},
      at_lower{range.lower + detail::kSaturationTolerance,
               range.lower + detail::kSaturationTolerance},
      axis_kept{},
      delivered{kDeliveredTolerance, kDeliveredTolerance},
      sign{-0.0, -0.0} {
  for (int a = 0; a < kNumAxes; ++a) {
    axis_kept[a] = ((controlled >> a) & 1U) ? ~std::uint64_t{0} : std::uint64_t{0};
  }
}

MatrixAllocator::MatrixAllocator(const MixingBasis& basis, CommandRange range)
    : mixing_(basis.mixing),
      mixing_by_column_(Eigen::Matrix<double, kMaxMotors, kNumAxes>::Zero()),
      effectiveness_(basis.effectiveness),
      range_(range),
      controlled_(basis.controlled),
      cycle_constants_(range, basis.controlled) {
  mixing_by_column_.topRows(mixing_.rows()) = mixing_;
}

bool MatrixAllocator::effectiveness_inverts_mixing(double tolerance) const {
  const Eigen::Matrix4d delivered = effectiveness_ * mixing_;
  for (int row = 0; row < kNumAxes; ++row) {
    if (!((controlled_ >> row) & 1U)) continue;
    for (int col = 0; col < kNumAxes; ++col) {
      const double expected = row == col ? 1.0 : 0.0;
      if (std::abs(delivered(row, col) - expected) > tolerance) return false;
    }
  }
  return true;
}

bool MatrixAllocator::equal_thrust_shares() const {
  const auto thrust = mixing_.col(index(Axis::kThrust));
  if (thrust.size() == 0 || !(thrust.minCoeff() > 0.0)) return false;
  constexpr double kSameShare = 1e-12;  // relative to the largest share
  return thrust.maxCoeff() - thrust.minCoeff() <= kSameShare * thrust.maxCoeff();
}

void MatrixAllocator::mix_linear(const AxisVector& demand, MotorVector& commands) const {
  const Eigen::Index n = mixing_.rows();
  commands.resize(n);
  detail::with_motor_count(n, [&](auto size) {
    constexpr int N = decltype(size)::value;
    detail::MotorsView<N>(commands.data(), n).noalias() =
        detail::ConstMixingColumnsView<N>(mixing_by_column_.data(), n, kNumAxes) * demand;
  });
}

AllocationResult MatrixAllocator::finish(const AxisVector& target, MotorVector& commands) const {
  const Eigen::Index n = commands.size();
  return detail::with_motor_count(n, [&](auto size) {
    constexpr int N = decltype(size)::value;
    detail::MotorsView<N> u(commands.data(), n);
    detail::clamp_into_range<N>(u, cycle_constants_);
    return detail::describe_fixed<N>(effectiveness_, target, commands.data(), n, cycle_constants_);
  });
}

}  // namespace motormix
