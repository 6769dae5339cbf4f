#pragma once
// The whole per-cycle pipeline: demand -> allocation strategy -> output stage.
// Inputs that are not finite are refused (the mixer answers with disarmed
// outputs and says so); inputs out of range are clamped and flagged. Nothing
// here allocates, logs or throws.

#include <motormix/allocation/allocation.hpp>
#include <motormix/allocation/motor_failure.hpp>
#include <motormix/axes.hpp>
#include <motormix/motor_vector.hpp>
#include <motormix/output/output_stage.hpp>

#include <cstdint>
#include <memory>
#include <vector>

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
  AllocationResult allocation;  // failed motors are neither saturated bit
  MotorMask failed = 0;         // motors treated as failed in this cycle (stopped)
  FailureHandling failure = FailureHandling::kNone;
  AxisMask held = kAllAxes;                   // axes the working motors still command
  AxisVector authority = AxisVector::Zero();  // per axis, for the failure set in force
};

class Mixer {
 public:
  Mixer(std::unique_ptr<const Allocator> allocator, OutputStage output_stage,
        ThrustRange thrust_range = ThrustRange::kUnipolar, FailurePlan failures = {});

  int motors() const { return allocator_->motors(); }
  const Allocator& allocator() const { return *allocator_; }
  const OutputStage& output_stage() const { return output_stage_; }
  const FailurePlan& failures() const { return failures_; }

  // dt_s: time since the previous cycle, for slew limits (0: none). failed:
  // motors to treat as failed (bits beyond motors() are ignored): they are
  // stopped (command 0, output at its disarmed value) and the others are
  // mixed with the matrix prepared for that set. A set that was not prepared
  // stops its motors all the same, mixes the rest with the prepared set of
  // its two lowest motors (or the healthy matrix) and reports the loss
  // (FailureHandling::kUnsupported).
  MixStatus mix(const AxisVector& demand, MixerOutput& out, double dt_s = 0.0,
                MotorMask failed = 0) const;
  void disarm(MixerOutput& out) const;

  // The prepared set for exactly `failed`, or nullptr.
  const PreparedFailure* prepared(MotorMask failed) const;

  // How `failed` is handled and what it leaves, as mix() reports it.
  struct FailureReport {
    FailureHandling handling = FailureHandling::kNone;
    AxisMask held = kAllAxes;
    AxisVector authority = AxisVector::Zero();
  };
  FailureReport failure_report(MotorMask failed) const;

 private:
  // Both for `failed` (already limited to the motors) given its prepared
  // set `exact` (prepared(failed), or nullptr): mix() looks it up once.
  const Allocator& allocator_for(MotorMask failed, const PreparedFailure* exact) const;
  FailureReport failure_report(MotorMask failed, const PreparedFailure* exact) const;

  std::unique_ptr<const Allocator> allocator_;
  OutputStage output_stage_;
  ThrustRange thrust_range_;
  FailurePlan failures_;
};

}  // namespace motormix
