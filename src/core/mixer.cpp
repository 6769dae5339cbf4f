#include <motormix/mixer.hpp>

#include <algorithm>
#include <utility>

namespace motormix {

Mixer::Mixer(std::unique_ptr<const Allocator> allocator, OutputStage output_stage,
             ThrustRange thrust_range)
    : allocator_(std::move(allocator)),
      output_stage_(std::move(output_stage)),
      thrust_range_(thrust_range) {}

MixStatus Mixer::mix(const AxisVector& demand, MixerOutput& out, double dt_s) const {
  if (!demand.allFinite()) {
    disarm(out);
    return MixStatus::kNonFiniteDemand;
  }
  const double thrust_low = thrust_floor(thrust_range_);
  AxisVector clamped;
  clamped << std::clamp(demand[index(Axis::kRoll)], -1.0, 1.0),
      std::clamp(demand[index(Axis::kPitch)], -1.0, 1.0),
      std::clamp(demand[index(Axis::kYaw)], -1.0, 1.0),
      std::clamp(demand[index(Axis::kThrust)], thrust_low, 1.0);
  out.allocation = allocator_->allocate(clamped, out.command);
  output_stage_.armed(out.command, out.output, out.direction, dt_s, out.armed);
  out.armed = true;
  return clamped == demand ? MixStatus::kOk : MixStatus::kDemandClamped;
}

void Mixer::disarm(MixerOutput& out) const {
  out.armed = false;
  out.command.setZero(motors());
  out.allocation = AllocationResult{};
  output_stage_.disarmed(out.output, out.direction);
}

}  // namespace motormix
