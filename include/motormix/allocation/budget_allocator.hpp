#pragma once
// Strategy `budget`: the team quad's budgets (throttle, roll+pitch, yaw
// shares of full power) with its "possible improvement": a negative
// contribution is taken from the power a motor has (down to zero) instead of
// being dropped, so roll, pitch and yaw act differentially. When a motor's
// roll and pitch together exceed their share, both are scaled down in
// proportion (the direction of the tilt is kept).

#include <motormix/allocation/allocation.hpp>
#include <motormix/allocation/legacy_budget_allocator.hpp>

namespace motormix {

class BudgetAllocator final : public MatrixAllocator {
 public:
  BudgetAllocator(const MixingMatrix& mixing, LegacyBudgets budgets);
  std::string_view name() const override { return "budget"; }
  AllocationResult allocate(const AxisVector& demand, MotorVector& commands) const override;

 private:
  LegacyBudgets budgets_;
};

}  // namespace motormix
