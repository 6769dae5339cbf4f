#include <motormix/allocation/legacy_budget_allocator.hpp>

#include <algorithm>

namespace motormix {

LegacyBudgetAllocator::LegacyBudgetAllocator(const MixingMatrix& mixing, LegacyBudgets budgets)
    : MatrixAllocator(mixing, CommandRange{0.0, 1.0}), budgets_(budgets) {}

AllocationResult LegacyBudgetAllocator::allocate(const AxisVector& demand,
                                                 MotorVector& commands) const {
  const Eigen::Index n = mixing_.rows();
  commands.resize(n);
  const auto positive_part = [](double v) { return std::max(0.0, v); };
  for (Eigen::Index i = 0; i < n; ++i) {
    double roll = positive_part(mixing_(i, index(Axis::kRoll)) * demand[index(Axis::kRoll)]) *
                  budgets_.roll_pitch;
    double pitch = positive_part(mixing_(i, index(Axis::kPitch)) * demand[index(Axis::kPitch)]) *
                   budgets_.roll_pitch;
    if (roll + pitch > budgets_.roll_pitch) {
      roll = budgets_.roll_pitch / 2.0;
      pitch = budgets_.roll_pitch / 2.0;
    }
    const double yaw =
        positive_part(mixing_(i, index(Axis::kYaw)) * demand[index(Axis::kYaw)]) * budgets_.yaw;
    const double thrust =
        positive_part(mixing_(i, index(Axis::kThrust)) * demand[index(Axis::kThrust)]) *
        budgets_.throttle;
    // Budgets sum to at most 1 (checked at configuration), so this clamp only
    // matters for coefficient tables with entries above 1.
    commands[i] = std::clamp(thrust + roll + pitch + yaw, 0.0, 1.0);
  }
  return finish(budgeted_target(demand, budgets_), commands);
}

}  // namespace motormix
