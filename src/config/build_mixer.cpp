#include <motormix/config/build_mixer.hpp>

#include "strategies.hpp"

#include <motormix/allocation/motor_failure.hpp>

#include <memory>

namespace motormix::config {

CommandRange command_range(const Config& config) {
  return CommandRange{thrust_floor(config.thrust_range()), 1.0};
}

namespace {

// The configured strategy on one basis (the healthy matrix or a failure's).
std::unique_ptr<const Allocator> make_allocator(const Config& config, const MixingBasis& basis) {
  return strategy_entry(config.strategy).make(config, basis, command_range(config));
}

}  // namespace

AxisVector authority_at_half_thrust(const Config& config, const MixingMatrix& mixing) {
  const bool aircraft = config.thrust_range() == ThrustRange::kUnipolar;
  const CommandRange range = command_range(config);
  return authority_of(mixing, aircraft ? 0.5 : 0.0, range.lower, range.upper);
}

FailurePlan failure_plan(const Config& config) {
  const bool aircraft = config.thrust_range() == ThrustRange::kUnipolar;
  FailureAllocatorFactory make;
  const StrategyEntry& entry = strategy_entry(config.strategy);
  if (entry.reallocates) {
    make = [&config, &entry](const FailureMixing& f, const MixingBasis& basis) {
      if (entry.make_after_failure)
        return entry.make_after_failure(config, f, basis, command_range(config));
      return entry.make(config, basis, command_range(config));
    };
  }
  return prepare_failures(config.mixing, command_range(config), aircraft ? 0.5 : 0.0, make);
}

Mixer build_mixer(const Config& config) {
  return Mixer(make_allocator(config, MixingBasis(config.mixing)), OutputStage(config.outputs),
               config.thrust_range(), failure_plan(config));
}

}  // namespace motormix::config
