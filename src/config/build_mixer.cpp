#include "config/build_mixer.hpp"

#include <motormix/legacy_budget_allocator.hpp>

#include <memory>

namespace motormix::config {

Mixer build_mixer(const Config& config) {
  std::unique_ptr<const Allocator> allocator;
  switch (config.strategy) {
    case Strategy::kLegacyBudget:
      allocator = std::make_unique<LegacyBudgetAllocator>(config.mixing, config.legacy_budgets);
      break;
  }
  return Mixer(std::move(allocator), OutputStage(config.outputs), config.thrust_range());
}

}  // namespace motormix::config
