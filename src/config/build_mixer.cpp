#include <motormix/config/build_mixer.hpp>

#include <motormix/budget_allocator.hpp>
#include <motormix/clip_allocator.hpp>
#include <motormix/legacy_budget_allocator.hpp>
#include <motormix/optimal_allocator.hpp>
#include <motormix/prioritized_allocator.hpp>
#include <motormix/shift_allocator.hpp>

#include <motormix/motor_failure.hpp>

#include <memory>

namespace motormix::config {

CommandRange command_range(const Config& config) {
  return CommandRange{thrust_floor(config.thrust_range()), 1.0};
}

namespace {

// The configured strategy on one basis (the healthy matrix or a failure's).
std::unique_ptr<const Allocator> make_allocator(const Config& config, const MixingBasis& basis) {
  const CommandRange range = command_range(config);
  switch (config.strategy) {
    case Strategy::kLegacyBudget:
      return std::make_unique<LegacyBudgetAllocator>(basis.mixing, config.legacy_budgets);
    case Strategy::kBudget:
      return std::make_unique<BudgetAllocator>(basis.mixing, config.legacy_budgets);
    case Strategy::kShift:
      return std::make_unique<ShiftAllocator>(basis, range);
    case Strategy::kClip:
      return std::make_unique<ClipAllocator>(basis, range);
    case Strategy::kPrioritized:
      return std::make_unique<PrioritizedAllocator>(basis, range, config.airmode,
                                                    config.yaw_headroom);
    case Strategy::kOptimal:
      return std::make_unique<OptimalAllocator>(basis, range, config.optimal);
  }
  return nullptr;
}

bool reallocates(Strategy strategy) {
  return strategy != Strategy::kLegacyBudget && strategy != Strategy::kBudget;
}

}  // namespace

AxisVector authority_at_half_thrust(const Config& config, const MixingMatrix& mixing) {
  const bool aircraft = config.thrust_range() == ThrustRange::kUnipolar;
  const CommandRange range = command_range(config);
  return authority_of(mixing, aircraft ? 0.5 : 0.0, range.lower, range.upper);
}

FailurePlan failure_plan(const Config& config) {
  FailurePlan plan;
  plan.healthy_effectiveness = effectiveness_of(config.mixing);
  plan.controlled = controlled_axes(config.mixing);
  plan.range = command_range(config);
  plan.healthy_authority = authority_at_half_thrust(config, config.mixing);
  if (!reallocates(config.strategy)) return plan;
  // Every single failure and every pair, whatever the motor count (at most
  // 16 + 120 sets): a switch in flight then only selects one.
  const int n = config.motors();
  const auto prepare = [&](MotorMask failed) {
    const FailureMixing f =
        derive_failure_mixing(plan.healthy_effectiveness, plan.controlled, failed);
    PreparedFailure p;
    p.failed = failed;
    p.allocator = make_allocator(config, MixingBasis(f.mixing, f.effectiveness, plan.controlled));
    p.held = f.held;
    p.authority = authority_at_half_thrust(config, f.mixing);
    plan.prepared.push_back(std::move(p));
  };
  for (int i = 0; i < n; ++i) {
    if (n > 1) prepare(MotorMask{1} << i);
    for (int j = i + 1; j < n && n > 2; ++j) prepare((MotorMask{1} << i) | (MotorMask{1} << j));
  }
  return plan;
}

Mixer build_mixer(const Config& config) {
  return Mixer(make_allocator(config, MixingBasis(config.mixing)), OutputStage(config.outputs),
               config.thrust_range(), failure_plan(config));
}

}  // namespace motormix::config
