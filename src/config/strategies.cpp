#include "strategies.hpp"

#include <motormix/allocation/budget_allocator.hpp>
#include <motormix/allocation/clip_allocator.hpp>
#include <motormix/allocation/legacy_budget_allocator.hpp>
#include <motormix/allocation/optimal_allocator.hpp>
#include <motormix/allocation/prioritized_allocator.hpp>
#include <motormix/allocation/shift_allocator.hpp>
#include <motormix/allocation/yaw_yielding_allocator.hpp>

#include <cstddef>
#include <iterator>

namespace motormix::config {

namespace {

using Made = std::unique_ptr<const Allocator>;

// `optimal` after a failure that leaves yaw one-sided (FailureMixing::
// yaw_free): yaw's weight times this.
constexpr double kFailedYawWeightShare = 0.01;

// In kStrategyNames' order (checked below), so an entry is found by index.
constexpr StrategyEntry kStrategies[] = {
    {Strategy::kLegacyBudget, false,
     [](const Config& c, const MixingBasis& b, const CommandRange&) -> Made {
       return std::make_unique<LegacyBudgetAllocator>(b.mixing, c.legacy_budgets);
     }},
    {Strategy::kBudget, false,
     [](const Config& c, const MixingBasis& b, const CommandRange&) -> Made {
       return std::make_unique<BudgetAllocator>(b.mixing, c.legacy_budgets);
     }},
    {Strategy::kShift, true,
     [](const Config&, const MixingBasis& b, const CommandRange& r) -> Made {
       return std::make_unique<ShiftAllocator>(b, r);
     }},
    {Strategy::kClip, true,
     [](const Config&, const MixingBasis& b, const CommandRange& r) -> Made {
       return std::make_unique<ClipAllocator>(b, r);
     }},
    {Strategy::kPrioritized, true,
     [](const Config& c, const MixingBasis& b, const CommandRange& r) -> Made {
       return std::make_unique<PrioritizedAllocator>(b, r, c.airmode, c.yaw_headroom,
                                                     c.tie_tolerance);
     },
     // With yaw one-sided, yaw yields to roll and pitch on the side it
     // cannot reach (yaw_yielding_allocator.hpp).
     [](const Config& c, const FailureMixing& f, const MixingBasis& b,
        const CommandRange& r) -> Made {
       if (!f.yaw_free)
         return std::make_unique<PrioritizedAllocator>(b, r, c.airmode, c.yaw_headroom,
                                                       c.tie_tolerance);
       return std::make_unique<YawYieldingAllocator>(b, *f.yaw_free, r, c.airmode, c.yaw_headroom,
                                                     c.tie_tolerance);
     }},
    {Strategy::kOptimal, true,
     [](const Config& c, const MixingBasis& b, const CommandRange& r) -> Made {
       return std::make_unique<OptimalAllocator>(b, r, c.optimal);
     },
     // Yaw gives way as it does for `prioritized`: with these motors out,
     // holding the demanded yaw at hover can leave no room for roll and
     // pitch, and the controller's yaw demand grows while the vehicle turns;
     // at the configured weight the trade kept roll and pitch 10-17 degrees
     // off on a hexa with one motor out (yaw 0.2 of roll's). At a hundredth,
     // yaw still decides between equally good answers.
     [](const Config& c, const FailureMixing& f, const MixingBasis& b,
        const CommandRange& r) -> Made {
       OptimalSettings settings = c.optimal;
       if (f.yaw_free) settings.weights[index(Axis::kYaw)] *= kFailedYawWeightShare;
       return std::make_unique<OptimalAllocator>(b, r, settings);
     }},
};

constexpr bool same_order() {
  if (std::size(kStrategies) != std::size(kStrategyNames)) return false;
  for (std::size_t i = 0; i < std::size(kStrategies); ++i) {
    if (kStrategies[i].strategy != kStrategyNames[i].value) return false;
  }
  return true;
}
static_assert(same_order(), "one strategy entry per name, in kStrategyNames' order");

}  // namespace

const StrategyEntry& strategy_entry(Strategy strategy) {
  for (const StrategyEntry& e : kStrategies) {
    if (e.strategy == strategy) return e;
  }
  return kStrategies[0];  // unreachable: every enumerator has an entry (static_assert above)
}

std::string reallocating_strategies() {
  std::string text;
  std::size_t left = 0;
  for (const StrategyEntry& e : kStrategies) left += e.reallocates ? 1 : 0;
  for (const StrategyEntry& e : kStrategies) {
    if (!e.reallocates) continue;
    --left;
    if (!text.empty()) text += left == 0 ? " or " : ", ";
    text += to_string(e.strategy);
  }
  return text;
}

}  // namespace motormix::config
