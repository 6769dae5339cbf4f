#pragma once
// The `failure_detection:` section: whether motormix looks for motors that
// stopped without anyone reporting it, from which sources, and how sure it
// must be. Absent (or enabled: false): no detection, and the ESC telemetry
// and attitude channels are not read for it. See docs/motor-failures.md.

#include <motormix/safety/failure_detector.hpp>

namespace motormix::config {

struct FailureDetection {
  // Ready for the core detector: thresholds from the section, the scale of
  // the rates source (torque per thrust, inertia, drag, motor lag) from the
  // `vehicle:` section.
  FailureDetectorSettings detector;
  // No motor is judged while the setpoint's throttle is below this: on the
  // ground, spinning up or landing, rpm and rates say little.
  double min_throttle = 0.25;
  // Electrical rpm divided by pole pairs (poles / 2) is mechanical rpm, for
  // ESCs that report eRPM only.
  int motor_poles = 14;
};

}  // namespace motormix::config
