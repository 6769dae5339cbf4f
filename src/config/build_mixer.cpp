#include <motormix/config/build_mixer.hpp>

#include <motormix/budget_allocator.hpp>
#include <motormix/clip_allocator.hpp>
#include <motormix/legacy_budget_allocator.hpp>
#include <motormix/optimal_allocator.hpp>
#include <motormix/prioritized_allocator.hpp>
#include <motormix/shift_allocator.hpp>

#include <memory>

namespace motormix::config {

CommandRange command_range(const Config& config) {
  return CommandRange{thrust_floor(config.thrust_range()), 1.0};
}

Mixer build_mixer(const Config& config) {
  const CommandRange range = command_range(config);
  std::unique_ptr<const Allocator> allocator;
  switch (config.strategy) {
    case Strategy::kLegacyBudget:
      allocator = std::make_unique<LegacyBudgetAllocator>(config.mixing, config.legacy_budgets);
      break;
    case Strategy::kBudget:
      allocator = std::make_unique<BudgetAllocator>(config.mixing, config.legacy_budgets);
      break;
    case Strategy::kShift:
      allocator = std::make_unique<ShiftAllocator>(config.mixing, range);
      break;
    case Strategy::kClip:
      allocator = std::make_unique<ClipAllocator>(config.mixing, range);
      break;
    case Strategy::kPrioritized:
      allocator = std::make_unique<PrioritizedAllocator>(config.mixing, range, config.airmode,
                                                         config.yaw_headroom);
      break;
    case Strategy::kOptimal:
      allocator = std::make_unique<OptimalAllocator>(config.mixing, range, config.optimal);
      break;
  }
  return Mixer(std::move(allocator), OutputStage(config.outputs), config.thrust_range());
}

}  // namespace motormix::config
