#pragma once
// Where the configured vehicle hovers: each rotor's thrust fraction and the
// setpoint throttle that gives it through the output stage (idle,
// thrust_model_factor, the channel's range) and the ESC's curve (the
// `vehicle:` section's esc range and thrust_expo). The gates that must open
// in hover (failure_detection.min_throttle, min_motor_thrust) default to
// fractions of it, and `run --check` names a gate the hover stays below.

#include <motormix/config/config.hpp>

namespace motormix::config {

struct HoverPoint {
  bool known = false;     // the vehicle section gives mass and thrust, and can lift itself
  double thrust = 0.0;    // each rotor's thrust fraction (0..1) in hover
  double throttle = 0.0;  // the setpoint throttle (0..1) that gives it
};

// Needs the output section and the vehicle section read. Each motor's
// command is taken as the throttle (what the mixer gives at zero torque on
// a vehicle whose rotors share the weight evenly).
HoverPoint hover_point(const Config& config);

}  // namespace motormix::config
