#include <motormix/config/build_mixer.hpp>

#include "strategies.hpp"

#include <motormix/optimal_allocator.hpp>
#include <motormix/yaw_yielding_allocator.hpp>

#include <motormix/motor_failure.hpp>

#include <memory>

namespace motormix::config {

CommandRange command_range(const Config& config) {
  return CommandRange{thrust_floor(config.thrust_range()), 1.0};
}

namespace {

// `optimal` after a failure that leaves yaw one-sided (FailureMixing::
// yaw_free): yaw's weight times this.
constexpr double kFailedYawWeightShare = 0.01;

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
  if (strategy_entry(config.strategy).reallocates) {
    make = [&config](const FailureMixing& f, const MixingBasis& basis) {
      if (config.strategy == Strategy::kPrioritized && f.yaw_free) {
        return std::unique_ptr<const Allocator>(std::make_unique<YawYieldingAllocator>(
            basis, *f.yaw_free, command_range(config), config.airmode, config.yaw_headroom,
            config.tie_tolerance));
      }
      if (config.strategy == Strategy::kOptimal && f.yaw_free) {
        // Yaw gives way as it does for `prioritized`: with these motors out,
        // holding the demanded yaw at hover can leave no room for roll and
        // pitch, and the controller's yaw demand grows while the vehicle
        // turns; at the configured weight the trade kept roll and pitch
        // 10-17 degrees off on a hexa with one motor out (yaw 0.2 of
        // roll's). At a hundredth, yaw still decides between equally good
        // answers.
        OptimalSettings settings = config.optimal;
        settings.weights[index(Axis::kYaw)] *= kFailedYawWeightShare;
        return std::unique_ptr<const Allocator>(
            std::make_unique<OptimalAllocator>(basis, command_range(config), settings));
      }
      return make_allocator(config, basis);
    };
  }
  return prepare_failures(config.mixing, command_range(config), aircraft ? 0.5 : 0.0, make);
}

Mixer build_mixer(const Config& config) {
  return Mixer(make_allocator(config, MixingBasis(config.mixing)), OutputStage(config.outputs),
               config.thrust_range(), failure_plan(config));
}

}  // namespace motormix::config
