#pragma once
// The whole per-cycle pipeline: demand -> allocation strategy -> output stage.
// Inputs that are not finite are refused (the mixer answers with disarmed
// outputs and says so); inputs out of range are clamped and flagged. Nothing
// here allocates, logs or throws.

#include <motormix/allocation.hpp>
#include <motormix/axes.hpp>
#include <motormix/motor_vector.hpp>
#include <motormix/output_stage.hpp>

#include <cstdint>
#include <memory>

namespace motormix {

enum class MixStatus : std::uint8_t {
  kOk = 0,
  kDemandClamped = 1,    // some axis was outside its range and was clamped
  kNonFiniteDemand = 2,  // NaN or infinite demand: outputs are the disarmed values
};

// Also the memory of the previous cycle: the slew limit works from `output`.
struct MixerOutput {
  bool armed = false;
  MotorVector command;          // normalized motor commands after allocation (0 when disarmed)
  MotorVector output;           // output-stage values, e.g. PWM microseconds
  DirectionVector direction{};  // magnitude/direction outputs: +1, -1, 0; others 0
  AllocationResult allocation;
};

class Mixer {
 public:
  Mixer(std::unique_ptr<const Allocator> allocator, OutputStage output_stage,
        ThrustRange thrust_range = ThrustRange::kUnipolar);

  int motors() const { return allocator_->motors(); }
  const Allocator& allocator() const { return *allocator_; }
  const OutputStage& output_stage() const { return output_stage_; }

  // dt_s: time since the previous cycle, for slew limits (0: none).
  MixStatus mix(const AxisVector& demand, MixerOutput& out, double dt_s = 0.0) const;
  void disarm(MixerOutput& out) const;

 private:
  std::unique_ptr<const Allocator> allocator_;
  OutputStage output_stage_;
  ThrustRange thrust_range_;
};

}  // namespace motormix
