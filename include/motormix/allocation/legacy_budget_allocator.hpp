#pragma once
// Strategy `legacy_budget`: the team quad mixer exactly as first specified.
//
// Per motor, each axis contributes coefficient * demand; negative roll, pitch
// and yaw contributions are dropped (a motor cannot push backwards, and the
// opposite motors get the positive share). Contributions are scaled by fixed
// budgets (throttle 60 %, roll+pitch 25 %, yaw 15 % by default) so their sum
// never exceeds full power. When the scaled roll and pitch contributions of a
// motor together exceed the roll+pitch budget, each is set to half of it: that
// is the original rule, kept bit for bit, even though it can shrink the larger
// of the two.

#include <motormix/allocation/allocation.hpp>
#include <motormix/allocation/allocation_settings.hpp>

namespace motormix {

// What the budgeted strategies aim to produce: the demand scaled by the
// budgets (their gains), against which what they miss is reported.
inline AxisVector budgeted_target(const AxisVector& demand, const LegacyBudgets& b) {
  return demand.cwiseProduct(AxisVector(b.roll_pitch, b.roll_pitch, b.yaw, b.throttle));
}

class LegacyBudgetAllocator final : public MatrixAllocator {
 public:
  LegacyBudgetAllocator(const MixingMatrix& mixing, LegacyBudgets budgets);

  std::string_view name() const override { return "legacy_budget"; }
  AllocationResult allocate(const AxisVector& demand, MotorVector& commands) const override;

 private:
  LegacyBudgets budgets_;
};

}  // namespace motormix
