#pragma once
// motormix inside another C++ program, without LCM: a configuration file in,
// a ready mixer out, one call per control cycle. Link motormix::config.
//
//   motormix::EmbeddedMixer mixer = motormix::EmbeddedMixer::from_file("quad_x.yaml");
//   motormix::Demand demand;
//   demand.thrust = 0.6;
//   demand.roll = 0.2;
//   motormix::MixReport r = mixer.mix(demand);   // r.command, r.pwm, r.saturated(i), r.unallocated
//
// Loading validates the whole configuration, exactly as `motormix run --check`
// does, and throws motormix::config::ConfigError naming the key path, the
// value found and what is allowed. After that, mix() never throws, never
// allocates and never returns an output outside its configured range,
// whatever the demand: NaN or infinite demands give the disarmed outputs
// (status kNonFiniteDemand), out-of-range ones are clamped (kDemandClamped).
//
// The channels, rates and failsafe settings of the file are validated too but
// belong to the LCM process; here the caller owns timing and arming.

#include <motormix/axes.hpp>
#include <motormix/config/config.hpp>
#include <motormix/mixer.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace motormix {

// One control cycle's demand, normalized.
struct Demand {
  double roll = 0.0;    // -1..1, positive lowers the right side
  double pitch = 0.0;   // -1..1, positive raises the nose
  double yaw = 0.0;     // -1..1, positive turns the nose right (wheels: turn left)
  double thrust = 0.0;  // 0..1 (ground vehicles: forward command -1..1)
};

// The result of one mix(). A view into the mixer: valid until its next call.
struct MixReport {
  MixStatus status;                  // kOk, kDemandClamped or kNonFiniteDemand
  bool armed;                        // false after disarm() or a non-finite demand
  const MotorVector& command;        // per motor, after allocation: 0..1 (reversible -1..1)
  const MotorVector& pwm;            // per motor, output-stage value (PWM microseconds by default)
  const DirectionVector& direction;  // H-bridge outputs: +1, -1, 0; otherwise 0
  MotorMask saturated_upper;         // bit i: motor i at its upper limit
  MotorMask saturated_lower;         // bit i: motor i at its lower limit
  std::uint8_t axis_limited;         // bit(Axis): that axis was not fully delivered
  const AxisVector& unallocated;     // roll, pitch, yaw, thrust: demanded minus produced
  MotorMask failed;                  // motors treated as failed (stopped) in this cycle
  FailureHandling failure;           // how that set was handled
  AxisMask held;                     // axes the working motors still command

  bool saturated(int motor) const { return ((saturated_upper | saturated_lower) >> motor) & 1U; }
  bool delivered(Axis axis) const { return (axis_limited & bit(axis)) == 0; }
};

class EmbeddedMixer {
 public:
  // `overrides` are "key.path=value" strings, as `--set` on the command line.
  static EmbeddedMixer from_file(const std::string& path,
                                 const std::vector<std::string>& overrides = {});
  static EmbeddedMixer from_yaml(const std::string& yaml_text,
                                 const std::vector<std::string>& overrides = {});

  int motors() const { return mixer_.motors(); }
  const std::vector<std::string>& motor_names() const { return config_.motor_names(); }
  const config::Config& config() const { return config_; }
  const Mixer& mixer() const { return mixer_; }

  // One cycle, armed. dt_s: time since the previous cycle, for the output
  // stage's slew limit (0: no limit this cycle). failed: motors to treat as
  // failed in this cycle, on top of the configuration's mixer.failed_motors
  // (bit i is motor i, m1 is bit 0); they are stopped and the others
  // reallocated (see motor_failure.hpp).
  MixReport mix(const Demand& demand, double dt_s = 0.0, MotorMask failed = 0);
  // Every output to its disarmed value.
  MixReport disarm();

 private:
  EmbeddedMixer(config::Config config, Mixer mixer);
  MixReport report(MixStatus status) const;

  config::Config config_;
  Mixer mixer_;
  MixerOutput out_;
};

}  // namespace motormix
