#pragma once
// The spin landing inside the control loop (config `motor_loss:`): when a
// four-rotor aircraft has exactly one failed motor (or two opposite ones
// that the vehicle's two-rotor plan can land), is armed and spooled up, and
// a fresh attitude is at hand, the core's SpinningDescent (TwoRotorDescent)
// takes over the outputs: the controller's roll, pitch and yaw are no longer followed; with
// a velocity in the attitude message its throttle is not either (the
// configured descent rate is flown), without one the throttle is the
// collective. Each cycle it turns the three thrusts into output-stage values
// through the vehicle's ESC curve and range (`vehicle:` section), the dead
// motors at their disarmed value. It lets go (and the loop mixes as before)
// when the attitude goes stale, when the failure set changes, or when
// the loop disarms; once it reports the vehicle landed, the loop disarms.

#include "loop/esc_curve.hpp"
#include "loop/input_samples.hpp"
#include "loop/latest_input.hpp"

#include <motormix/config/config.hpp>
#include <motormix/mixer.hpp>
#include <motormix/safety/spinning_descent.hpp>
#include <motormix/safety/two_rotor_descent.hpp>

#include <cstdint>
#include <vector>

namespace motormix::loop {

struct LandingReport {
  DescentPhase state = DescentPhase::kOff;
  int motor = -1;  // the failed motor it lands without (0-based; the first of two), -1 when off
  MotorMask failed = 0;  // every motor it lands without
  double measured_rate_rad_s =
      0.0;                      // |rates| measured (the configured one: motor_loss.spin_rate_rad_s)
  double axis_error_deg = 0.0;  // spin axis from where it should point
};

class LandingRunner {
 public:
  // config.motor_loss must be set.
  explicit LandingRunner(const config::Config& config);

  struct Inputs {
    bool flying = false;     // armed or in a failsafe, spooled up, no motor test
    bool may_start = false;  // armed: a failsafe may keep a landing going, never start one
    MotorMask failed = 0;    // the failure set in force
    const LatestInput<AttitudeSample>* attitude = nullptr;
    double throttle = 0.0;  // the setpoint's
  };
  // One cycle. Returns true when it drives the outputs: `out` then holds
  // them. report().state == DescentPhase::kLanded asks the loop to disarm.
  bool cycle(const Inputs& in, std::int64_t now_us, const OutputStage& stage, MixerOutput& out);
  // The loop disarmed: a landing in progress ends; "landed" is kept for the
  // status until the next arming.
  void disarmed();
  void armed();
  const LandingReport& report() const { return report_; }
  const SpinningDescent& descent() const { return descent_; }
  const TwoRotorDescent& two_rotor_descent() const { return two_rotor_; }

 private:
  void stop();
  bool two_rotor_cycle(const Inputs& in, std::int64_t now_us, const OutputStage& stage,
                       MixerOutput& out);
  void drive(const DescentCommand& c, MotorMask failed, const OutputStage& stage, MixerOutput& out);

  SpinningDescent descent_;
  TwoRotorDescent two_rotor_;
  std::int64_t attitude_timeout_us_;
  EscCurve curve_;
  LandingReport report_;
};

}  // namespace motormix::loop
