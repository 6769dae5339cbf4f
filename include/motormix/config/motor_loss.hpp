#pragma once
// The `motor_loss:` section: what a four-rotor aircraft does when one of its
// motors fails (configured, reported on motor_status or found by the
// detector). `spin_landing` gives up yaw and lands spinning (the core's
// SpinningDescent, flown from the attitude input); `off` keeps mixing the
// controller's demand over the motors left, as every other vehicle does.
// Default: `auto`, which is spin_landing on a four-rotor aircraft whose
// `vehicle:` section has a relaxed hover for every motor, and off otherwise.
// See docs/motor-loss-landing.md.

#include <motormix/safety/spinning_descent.hpp>

#include <string>

namespace motormix::config {

struct MotorLoss {
  // The vehicle (from the `vehicle:` section) and the controller's settings.
  SpinningDescentModel model;
  SpinningDescentSettings settings;
  // With each motor stopped, at settings.spin_rate_rad_s: solved once, here.
  SpinEquilibria equilibria{};
  // An attitude older than this cannot fly the vehicle: the loop does what
  // it would without the mode.
  double attitude_timeout_s = 0.05;
  double gyro_range_rad_s = 0.0;  // the spin rate must stay well inside it
  // How settings.spin_rate_rad_s was chosen when the configuration did not
  // name one and the default has no equilibrium for this vehicle ("" when
  // it is the default or the configuration's).
  std::string spin_rate_chosen;
};

}  // namespace motormix::config
