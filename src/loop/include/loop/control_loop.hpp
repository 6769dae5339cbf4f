#pragma once
// The mixer process's decisions, with time passed in: which inputs are in
// force, whether they are stale, whether the motors may spin, and what to
// output. No LCM and no clock here, so a bus, a log replay and a test all
// drive the same logic. It is composed of small units, each with its rules
// in its own header: LatestInput (one freshness rule for every input),
// Arming (arming and failsafe), MotorTestRunner, SpoolUp and FailureSet.
//
// Rules kept here (documented in docs/running.md):
// - While armed, a setpoint or pid older than its timeout puts the loop in
//   failsafe (arming.hpp). The configured action decides the outputs:
//   disarmed values (default), the last valid inputs for at most
//   hold_last_ms and then disarmed, or idle (armed, zero demand).
// - A cycle that comes later after the previous one than the shorter input
//   timeout (the process was frozen or starved) is a failsafe too while
//   armed: for that long nobody watched the inputs, and the messages that
//   arrived meanwhile may not all have been read yet.
// - Rejected messages (non-finite, out of range, out of order, from the
//   future, wrong size) are counted and otherwise ignored: the previous
//   valid message stays in force and keeps ageing toward its timeout.
// - A motor_status whose num_motors differs from the mixer's is rejected.
// - With battery compensation configured, the thrust demand is multiplied by
//   the gain of the filtered voltage while it is fresh and plausible; a
//   stale, missing or implausible voltage means gain 1 (no compensation).
// - With failure_detection configured, the detector (detection_runner.hpp)
//   judges, at the start of each cycle, the outputs the motors are running
//   on. It judges only while armed and spooled up, with no motor test, with
//   a fresh setpoint at or above failure_detection.min_throttle; whatever it
//   declares joins the failure set at once (this cycle mixes without it)
//   and stands until the loop disarms. ESC telemetry and attitude messages
//   are read only when a source uses them.
// - With motor_loss configured (a quad), one failed motor while armed and
//   spooled up hands the outputs to the spin landing (landing_runner.hpp)
//   for as long as a fresh attitude arrives; it keeps flying through a
//   failsafe that would otherwise keep mixing or disarm (the commands it
//   would miss are ones it no longer follows) but never starts in one, ends
//   when the setpoint disarms, and disarms the loop itself once landed.
// - What a cycle reports is what is true in that cycle: a cycle that does
//   not mix (disarmed, failsafe with disarmed outputs, motor test) reports
//   no saturation and nothing unallocated.

#include <motormix/config/config.hpp>
#include "loop/arming.hpp"
#include "loop/counters.hpp"
#include "loop/detection_runner.hpp"
#include "loop/failure_set.hpp"
#include "loop/input_samples.hpp"
#include "loop/landing_runner.hpp"
#include "loop/latest_input.hpp"
#include "loop/loop_state.hpp"
#include "loop/message_checks.hpp"
#include "loop/motor_test_runner.hpp"
#include "loop/physical_inputs.hpp"
#include "loop/spool_up.hpp"

#include <motormix/mixer.hpp>

#include <motormix/output/battery_compensation.hpp>

#include <array>
#include <cstdint>
#include <optional>

namespace motormix::loop {

struct CycleResult {
  MixerOutput mix;
  LoopState state = LoopState::kDisarmed;
  FailsafeReason reason = FailsafeReason::kNone;
  bool state_changed = false;  // state differs from the previous cycle's
  // A setpoint asked to arm and was refused in this cycle, and why (once
  // per request: the node logs it).
  Arming::Refusal arming_refused = Arming::Refusal::kNone;
  // The latest request's refusal, until the loop arms (the status says it).
  Arming::Refusal last_arming_refusal = Arming::Refusal::kNone;
  bool setpoint_stale = true;
  bool pid_stale = true;
  std::int64_t setpoint_utime = 0;  // utime of the setpoint in force, 0 if none
  std::int64_t pid_utime = 0;       // utime of the pid in force, 0 if none
  MotorMask failed = 0;             // failure set in force (config and motor_status)
  FailureHandling failure = FailureHandling::kNone;  // how that set is handled
  AxisMask held = kAllAxes;                          // axes the working motors still command
  AxisVector authority = AxisVector::Zero();         // per axis, for that set
  BatteryState battery = BatteryState::kOff;
  double battery_v = 0.0;    // filtered, 0 before the first plausible reading
  double thrust_gain = 1.0;  // applied to the thrust demand in this cycle
  // Milliseconds since the last accepted setpoint, pid, battery and
  // motor_status message; -1 if none yet.
  std::array<double, 4> input_age_ms{-1.0, -1.0, -1.0, -1.0};
  bool spooling_up = false;  // armed, outputs ramping up since arming
  double spool_up = 0.0;     // ramp progress 0..1 (1 once done, 0 while not armed)
  // motormix's own detector: what it declared since arming (also in
  // `failed`), the latest declaration, silent ESCs; and whether it declared
  // something new in this cycle (the node then reports it on motor_status).
  Detection detection;
  bool detection_changed = false;
  double attitude_age_ms = -1.0;
  double esc_telemetry_age_ms = -1.0;  // since the last accepted esc_telemetry, -1 if none
  // From the configuration: the detector's sources (DetectorSources bits, 0
  // without failure_detection) and whether motor_loss is configured.
  std::uint8_t detector_sources = 0;
  bool motor_loss_on = false;
  LandingReport landing;  // the spin landing (motor_loss)
  bool landing_changed = false;
  int motor_test = -1;  // motor spinning alone (0-based), -1 when none
  double motor_test_throttle = 0.0;
  bool motor_test_changed = false;            // a test started or ended in this cycle
  std::int64_t motor_test_request_utime = 0;  // the last request handled
  MotorTestResult motor_test_result = MotorTestResult::kOk;  // its answer
};

class ControlLoop {
 public:
  ControlLoop(const config::Config& config, Mixer mixer);

  // now_us: a monotonic clock in microseconds (receive time, not the
  // publisher's utime, which may come from another clock). wall_us: this
  // host's wall clock, to spot messages from the future.
  Rejection on_setpoint(const SetpointSample& sample, std::int64_t now_us, std::int64_t wall_us);
  Rejection on_pid(const PidSample& pid, std::int64_t now_us, std::int64_t wall_us);
  Rejection on_motor_status(const MotorStatusSample& sample, std::int64_t now_us,
                            std::int64_t wall_us);
  Rejection on_battery(const BatterySample& sample, std::int64_t now_us, std::int64_t wall_us);
  // A motor test request; its answer is also in the next cycle's result.
  MotorTestResult on_motor_test(const MotorTestSample& sample, std::int64_t now_us,
                                std::int64_t wall_us);
  // Read only when failure detection uses them (else ignored, kNone).
  Rejection on_esc_telemetry(const EscTelemetrySample& sample, std::int64_t now_us,
                             std::int64_t wall_us);
  Rejection on_attitude(const AttitudeSample& sample, std::int64_t now_us, std::int64_t wall_us);
  // Which optional inputs a loop of `config` reads, from the configuration
  // alone (the routing of its channels follows them: messages::InputRoutes):
  // ESC telemetry for the detector's telemetry source, the attitude for its
  // rates source or the spin landing.
  static bool reads_esc_telemetry(const config::Config& config);
  static bool reads_attitude(const config::Config& config);
  bool reads_esc_telemetry() const { return detection_ && detection_->uses_telemetry(); }
  bool reads_attitude() const {
    return (detection_ && detection_->uses_rates()) || landing_.has_value();
  }

  // One control cycle at time now_us. The returned reference stays valid
  // until the next call.
  const CycleResult& cycle(std::int64_t now_us);

  const CycleResult& last() const { return result_; }
  // The failure detector as it runs (nullptr without failure_detection):
  // what the start-up banner reports.
  const DetectionRunner* detection() const { return detection_ ? &*detection_ : nullptr; }
  // The conversion from newtons and newton-metres (inputs.units: physical).
  const PhysicalInputs* physical_inputs() const { return physical_ ? &*physical_ : nullptr; }
  const Counters& counters() const { return counters_; }
  const Mixer& mixer() const { return mixer_; }

 private:
  void count(Rejection rejection);
  bool from_future(std::int64_t utime, std::int64_t wall_us);
  void enter_failsafe(FailsafeReason reason, std::int64_t now_us);
  // ramp: spool-up progress, 1 when none.
  void mix_inputs(const AxisVector& demand, std::int64_t now_us, double ramp = 1.0);
  // The cycle result's view of the vehicle: failed motors and how they
  // are handled, battery state and thrust gain, and each input's age.
  void record_vehicle_state(std::int64_t now_us);
  // The detector's turn, before mixing: judges the outputs of the previous
  // cycle and adds what it declares to the failure set. ramp: spool-up
  // progress (1 once spooled up).
  void detect(std::int64_t now_us, bool setpoint_fresh, double ramp);
  // The spin landing's turn, after mixing: may replace the outputs, or disarm.
  void land(std::int64_t now_us, double ramp);

  Mixer mixer_;
  ThrustRange thrust_range_;
  config::YawSource yaw_source_;
  std::int64_t setpoint_timeout_us_;
  std::int64_t pid_timeout_us_;
  config::FailsafeAction failsafe_action_;
  std::int64_t hold_last_us_;
  std::int64_t max_future_us_;
  std::int64_t last_cycle_us_ = kNever;

  LatestInput<SetpointSample> setpoint_;
  LatestInput<PidSample> pid_;
  LatestInput<BatterySample> battery_reading_;
  LatestInput<MotorStatusSample> motor_status_;
  std::optional<BatteryCompensation> battery_;
  Arming arming_;
  MotorTestRunner motor_test_;
  SpoolUp spool_up_;
  FailureSet failures_;
  std::optional<DetectionRunner> detection_;
  // inputs.units physical: newtons and newton-metres to demands, at
  // reception (every later rule reads demands: arming, the gates).
  std::optional<PhysicalInputs> physical_;
  std::optional<LandingRunner> landing_;
  LoopState previous_state_ = LoopState::kDisarmed;  // the state the previous cycle ended in
  LatestInput<AttitudeSample> attitude_;
  std::array<std::int64_t, kMaxEscReadings> esc_last_utime_;
  std::int64_t esc_received_us_ = -1;  // loop clock of the last accepted esc_telemetry

  CycleResult result_;
  Counters counters_;
};

}  // namespace motormix::loop
