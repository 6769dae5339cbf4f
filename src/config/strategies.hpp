#pragma once
// The allocation strategies, one entry each: whether it reallocates (drives
// motors that push both ways and redistributes after a motor failure), how
// it is built on a basis, and how on a failure's basis. The reader, the failure plan and the mixer
// all ask this table; the names come from kStrategyNames (config.hpp). Private to the config
// library.

#include <motormix/config/config.hpp>

#include <motormix/allocation/allocation.hpp>
#include <motormix/allocation/motor_failure.hpp>

#include <memory>
#include <string>

namespace motormix::config {

struct StrategyEntry {
  Strategy strategy;
  // false for the budget strategies: fixed shares of a unipolar output, no
  // failure reallocation.
  bool reallocates;
  std::unique_ptr<const Allocator> (*make)(const Config& config, const MixingBasis& basis,
                                           const CommandRange& range);
  // On a failure's basis (reallocating strategies), when it differs from
  // `make` there (a failure that leaves yaw one-sided); null: `make`.
  std::unique_ptr<const Allocator> (*make_after_failure)(const Config& config,
                                                         const FailureMixing& failure,
                                                         const MixingBasis& basis,
                                                         const CommandRange& range) = nullptr;
};

const StrategyEntry& strategy_entry(Strategy strategy);
// "shift, clip, prioritized or optimal": the strategies that reallocate.
std::string reallocating_strategies();

}  // namespace motormix::config
