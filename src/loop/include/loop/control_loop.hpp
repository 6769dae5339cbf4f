#pragma once
// The mixer process's decisions, with time passed in: which inputs are in
// force, whether they are stale, whether the motors may spin, and what to
// output. No LCM and no clock here, so a bus, a log replay and a test all
// drive the same logic.
//
// Safety rules (documented in docs/running.md):
// - Outputs are the disarmed values until a fresh setpoint with armed=true
//   arrives while a fresh pid is in force, and only after a setpoint with
//   armed=false has been seen: arming needs an explicit disarmed -> armed
//   transition, so a mixer (re)started mid-command never jumps the motors.
// - Arming is refused while |throttle| is above inputs.arm_max_throttle.
// - While armed, a setpoint or pid older than its timeout puts the loop in
//   failsafe. The configured action decides the outputs: disarmed values
//   (default), the last valid inputs for at most hold_last_ms and then
//   disarmed, or idle (armed, zero demand). Leaving failsafe needs fresh
//   inputs and a new disarmed -> armed transition.
// - A cycle that comes later after the previous one than the shorter input
//   timeout (the process was frozen or starved) is a failsafe too while
//   armed: for that long nobody watched the inputs, and the messages that
//   arrived meanwhile may not all have been read yet.
// - Rejected messages (non-finite, out of range, out of order) are counted
//   and otherwise ignored: the previous valid message stays in force and
//   keeps ageing toward its timeout.
// - Motors are failed by the configuration (mixer.failed_motors, always) and
//   by the latest accepted motor_status message (until the next one says
//   otherwise: a silent failure detector does not bring a motor back). A
//   motor_status whose num_motors differs from the mixer's is rejected.
// - After each disarmed -> armed transition (so after any disarm or
//   failsafe too), the outputs spool up over output.spool_up_s: the demand
//   is scaled by the ramp r = time armed / spool_up_s, and each output is
//   its disarmed value (taken into [min, max]: output.min for an ESC whose
//   disarmed value is below it) plus r times the way to its mixed value, so
//   it rises from stopped through idle, never overshoots what it is mixed
//   to and never leaves the output range.
// - A motor test (motor_test_t) spins one motor alone through the output
//   stage while the outputs stay disarmed (armed = false), and is obeyed only
//   when motor_test.enabled, the loop is disarmed, no armed setpoint arrived
//   within the setpoint timeout, and throttle and duration are within
//   motor_test.max_throttle and max_seconds. It ends at its duration, at the
//   first armed setpoint, when a new test replaces it, or on request
//   (motor 0); every refusal is counted with its reason.
// - With battery compensation configured, the thrust demand is multiplied by
//   the gain of the filtered voltage while it is fresh and plausible; a
//   stale, missing or implausible voltage means gain 1 (no compensation).

#include <motormix/config/config.hpp>
#include "loop/input_samples.hpp"
#include "loop/message_checks.hpp"

#include <motormix/mixer.hpp>

#include <motormix/battery_compensation.hpp>

#include <array>
#include <cstdint>
#include <limits>
#include <optional>

namespace motormix::loop {

enum class LoopState : std::int8_t { kDisarmed = 0, kArmed = 1, kFailsafe = 2 };
enum class FailsafeReason : std::int8_t {
  kNone = 0,
  kSetpointStale = 1,
  kPidStale = 2,
  kInvalidInput = 3,
  kLoopStalled = 4,  // the mixer itself ran no cycle for longer than an input timeout
};

const char* to_string(LoopState state);
const char* to_string(FailsafeReason reason);

// The answer to a motor test request (mixer_status_t MOTOR_TEST_*).
enum class MotorTestResult : std::int8_t {
  kOk = 0,
  kRefusedDisabled = 1,
  kRefusedNotDisarmed = 2,
  kRefusedArmedSetpoint = 3,
  kRefusedThrottle = 4,
  kRefusedDuration = 5,
  kRefusedMotor = 6,
  kRefusedInvalid = 7,
};
const char* to_string(MotorTestResult result);

struct Counters {
  std::int64_t cycles = 0;
  std::int64_t setpoint_received = 0;
  std::int64_t pid_received = 0;
  std::int64_t rejected_decode = 0;
  std::int64_t rejected_nonfinite = 0;
  std::int64_t rejected_range = 0;
  std::int64_t rejected_out_of_order = 0;
  std::int64_t rejected_future = 0;
  std::int64_t failsafe_events = 0;
  std::int64_t arming_refused = 0;  // armed requests refused by the arming check
  std::int64_t motor_status_received = 0;
  std::int64_t battery_received = 0;
  std::int64_t rejected_size = 0;  // wrong array sizes
  std::int64_t motor_tests_started = 0;
  std::int64_t motor_tests_refused = 0;

  std::int64_t rejected() const {
    return rejected_decode + rejected_nonfinite + rejected_range + rejected_out_of_order +
           rejected_future + rejected_size;
  }
};

struct CycleResult {
  MixerOutput mix;
  LoopState state = LoopState::kDisarmed;
  FailsafeReason reason = FailsafeReason::kNone;
  bool state_changed = false;  // state differs from the previous cycle's
  bool setpoint_stale = true;
  bool pid_stale = true;
  std::int64_t setpoint_utime = 0;         // utime of the setpoint in force, 0 if none
  std::int64_t pid_utime = 0;              // utime of the pid in force, 0 if none
  AllocationResult last_armed_allocation;  // from the most recent armed cycle
  MotorMask failed = 0;                    // failure set in force (config and motor_status)
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
  int motor_test = -1;       // motor spinning alone (0-based), -1 when none
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
  void on_undecodable() { ++counters_.rejected_decode; }

  // One control cycle at time now_us. The returned reference stays valid
  // until the next call.
  const CycleResult& cycle(std::int64_t now_us);

  const CycleResult& last() const { return result_; }
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

  Mixer mixer_;
  ThrustRange thrust_range_;
  config::YawSource yaw_source_;
  std::int64_t setpoint_timeout_us_;
  std::int64_t pid_timeout_us_;
  config::FailsafeAction failsafe_action_;
  std::int64_t hold_last_us_;
  std::int64_t max_future_us_;
  double arm_max_throttle_;
  std::int64_t failsafe_since_us_ = 0;

  static constexpr std::int64_t kNever = std::numeric_limits<std::int64_t>::min();
  SetpointSample setpoint_;
  PidSample pid_;
  std::int64_t setpoint_received_us_ = kNever;
  std::int64_t pid_received_us_ = kNever;
  std::int64_t last_setpoint_utime_ = kNever;
  std::int64_t last_pid_utime_ = kNever;
  std::int64_t last_cycle_us_ = kNever;
  MotorMask config_failed_ = 0;
  MotorMask reported_failed_ = 0;  // from the latest accepted motor_status
  // The failure report of the set in force, looked up again only when the
  // set changes (Mixer::mix looks the set up for itself every cycle).
  bool failure_report_known_ = false;
  MotorMask failure_report_for_ = 0;
  std::int64_t motor_status_received_us_ = kNever;
  std::int64_t last_motor_status_utime_ = kNever;
  std::optional<BatteryCompensation> battery_;
  std::int64_t battery_received_us_ = kNever;
  std::int64_t last_battery_utime_ = kNever;
  std::int64_t spool_up_us_ = 0;
  std::int64_t armed_since_us_ = 0;
  config::MotorTestSettings motor_test_settings_;
  std::int64_t last_armed_setpoint_us_ = kNever;  // receive time of the last armed setpoint
  std::int64_t last_motor_test_utime_ = kNever;
  int test_motor_ = -1;  // running test, 0-based
  double test_throttle_ = 0.0;
  std::int64_t test_end_us_ = 0;
  bool test_changed_ = false;  // since the last cycle
  void end_motor_test();
  void spin_test_motor();
  bool arm_permitted_ = false;
  bool arm_refused_logged_ = false;  // a disarmed setpoint has been seen since boot or failsafe

  CycleResult result_;
  Counters counters_;
};

}  // namespace motormix::loop
