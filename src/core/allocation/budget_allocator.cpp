#include <motormix/allocation/budget_allocator.hpp>

#include <cmath>

namespace motormix {

BudgetAllocator::BudgetAllocator(const MixingMatrix& mixing, LegacyBudgets budgets)
    : MatrixAllocator(mixing, CommandRange{0.0, 1.0}), budgets_(budgets) {}

AllocationResult BudgetAllocator::allocate(const AxisVector& demand, MotorVector& commands) const {
  const Eigen::Index n = mixing_.rows();
  commands.resize(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    double roll = mixing_(i, index(Axis::kRoll)) * demand[index(Axis::kRoll)] * budgets_.roll_pitch;
    double pitch =
        mixing_(i, index(Axis::kPitch)) * demand[index(Axis::kPitch)] * budgets_.roll_pitch;
    const double tilt = std::abs(roll) + std::abs(pitch);
    if (tilt > budgets_.roll_pitch) {
      roll *= budgets_.roll_pitch / tilt;
      pitch *= budgets_.roll_pitch / tilt;
    }
    const double yaw = mixing_(i, index(Axis::kYaw)) * demand[index(Axis::kYaw)] * budgets_.yaw;
    const double thrust =
        mixing_(i, index(Axis::kThrust)) * demand[index(Axis::kThrust)] * budgets_.throttle;
    commands[i] = thrust + roll + pitch + yaw;  // clamped to 0..1 by finish()
  }
  return finish(budgeted_target(demand, budgets_), commands);
}

}  // namespace motormix
