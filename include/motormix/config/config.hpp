#pragma once
// A validated, immutable description of one motormix process: which vehicle,
// which strategy, which output ranges, which channels and rates. Built once
// at start-up by load_config(); nothing downstream re-validates it.

#include <motormix/allocation/allocation_settings.hpp>
#include <motormix/config/config_error.hpp>
#include <motormix/config/failure_detection.hpp>
#include <motormix/config/hardware.hpp>
#include <motormix/config/motor_loss.hpp>
#include <motormix/config/security.hpp>
#include <motormix/config/vehicle_physics.hpp>
#include <motormix/effectiveness/geometry.hpp>
#include <motormix/effectiveness/mixing_matrix.hpp>
#include <motormix/effectiveness/vehicle.hpp>
#include <motormix/enum_names.hpp>
#include <motormix/motor_vector.hpp>
#include <motormix/output/battery_compensation.hpp>
#include <motormix/output/output_stage.hpp>

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace motormix::config {

// ConfigError (config_error.hpp) is thrown at set-up only, never inside a
// control cycle.

enum class Strategy { kLegacyBudget, kBudget, kShift, kClip, kPrioritized, kOptimal };
enum class YawSource { kSetpoint, kPid };
// What setpoint_t and pid_t carry: demands of -1..1 (0..1 for the
// throttle) in the mixing table's signs, or newtons and newton-metres
// (docs/inputs-in-physical-units.md).
enum class InputUnits { kNormalized, kPhysical };

struct Channels {
  std::string setpoint = "SETPOINT";
  std::string pid = "PID";
  std::string motor_pwm = "MOTOR_PWM";
  std::string status = "MIXER_STATUS";
  std::string motor_status = "MOTOR_STATUS";
  std::string battery = "BATTERY";
  std::string motor_test = "MOTOR_TEST";
  std::string esc_telemetry = "ESC_TELEMETRY";
  std::string attitude = "ATTITUDE";
  std::string output_status = "OUTPUT_STATUS";  // motormix output's own state
  std::string esc_command = "ESC_COMMAND";      // DShot special commands for motormix output
  std::string lockstep = "MOTORMIX_LOCKSTEP";   // a simulator's clock (run --lockstep)
};

// `motormix motor-test`: a disarmed mixer spins one motor alone on request.
struct MotorTestSettings {
  bool enabled = true;
  double max_throttle = 0.15;  // largest normalized command a test may ask for
  double max_seconds = 3.0;    // longest test
};

// What the outputs do when an input goes stale, is lost or turns invalid
// while armed.
enum class FailsafeAction {
  kDisarm,    // disarmed values at once (default)
  kHoldLast,  // keep mixing the last valid inputs for hold_last_s, then disarm
  kIdle,      // armed with zero demand (idle spin) until re-armed
};

struct Inputs {
  YawSource yaw_source = YawSource::kSetpoint;
  double setpoint_timeout_s = 0.100;  // older setpoints are stale
  double pid_timeout_s = 0.100;       // older pid messages are stale
  FailsafeAction failsafe = FailsafeAction::kDisarm;
  double hold_last_s = 0.5;       // kHoldLast: how long, at most
  double max_future_s = 1.0;      // utime further ahead of this host's clock: rejected
  double arm_max_throttle = 0.1;  // arming refused while |throttle| is above this
  InputUnits units = InputUnits::kNormalized;
};

enum class PublishMode {
  kTimer,    // outputs on the loop timer only
  kOnInput,  // also right after each accepted pid message (the timer stays as watchdog)
};

struct Realtime {
  int priority = 0;          // SCHED_FIFO priority 1..99; 0 leaves the scheduler alone
  std::vector<int> cpus;     // CPU affinity; empty leaves it alone
  bool lock_memory = false;  // mlockall
};

struct Config {
  std::string name;  // for logs and status
  Vehicle geometry;  // the `geometry:` section: preset, rotors, effectiveness, table or wheels
  std::string geometry_source;  // which form described it, for logs
  Normalization normalization = Normalization::kAxisMax;
  std::optional<MixingDerivation> derivation;  // set when derived from an effectiveness matrix
  std::optional<WheelBase> wheel_base;         // set for wheeled vehicles
  MixingMatrix
      mixing;  // the matrix the mixer applies; rows: motors; columns: roll, pitch, yaw, thrust

  Strategy strategy = Strategy::kLegacyBudget;
  LegacyBudgets legacy_budgets;                 // legacy_budget and budget
  AirmodeLimits airmode;                        // prioritized: off unless set
  double yaw_headroom = 0.15;                   // prioritized
  double tie_tolerance = kDefaultTieTolerance;  // prioritized
  OptimalSettings optimal;                      // optimal
  MotorMask failed_motors = 0;  // mixer.failed_motors: stopped from the start, bit i = motor i

  std::optional<BatterySettings> battery;  // set: thrust compensated for the pack voltage

  std::vector<OutputChannel> outputs;  // one per motor
  std::string output_unit = "us";      // for logs and tools
  // After each disarmed -> armed transition, outputs ramp from their disarmed
  // values to the mixed command over this time, the demand scaled with the
  // ramp (output.spool_up_s; 0: none).
  double spool_up_s = 0.0;

  Inputs inputs;
  Channels channels;
  MotorTestSettings motor_test;
  double loop_rate_hz = 400.0;
  double status_rate_hz = 10.0;
  PublishMode publish = PublishMode::kTimer;
  Realtime realtime;
  VehiclePhysics vehicle_model;  // the `vehicle:` section: what motormix sim flies
  // Set when `failure_detection:` is present and enabled.
  std::optional<FailureDetection> failure_detection;
  // Set when a four-rotor aircraft lands spinning after losing a motor
  // (`motor_loss:`); otherwise motor_loss_off says why not.
  std::optional<MotorLoss> motor_loss;
  std::string motor_loss_off;
  // The `hardware:` section: what `motormix output` drives.
  Hardware hardware;
  // The `security:` section: signing on the bus.
  Security security;
  std::uint64_t hash = 0;  // of the configuration text and overrides, reported in status

  int motors() const { return static_cast<int>(mixing.rows()); }
  const std::vector<std::string>& motor_names() const { return geometry.motor_names; }
  // A motor as users name it: its name, or its number as `motormix matrix`
  // prints it (1-based). 0-based index, -1 when it is neither.
  int motor_index(const std::string& text) const;
  ThrustRange thrust_range() const { return geometry.thrust_range; }
  std::string description() const;
  // One line on what a failed motor makes the mixer do: the spin landing
  // and the attitude channel it needs, or why there is none. Empty for
  // vehicles that keep flying on the motors left (six rotors or more).
  std::string motor_loss_summary() const;
};

inline constexpr EnumName<Strategy> kStrategyNames[] = {
    {Strategy::kLegacyBudget, "legacy_budget"},
    {Strategy::kBudget, "budget"},
    {Strategy::kShift, "shift"},
    {Strategy::kClip, "clip"},
    {Strategy::kPrioritized, "prioritized"},
    {Strategy::kOptimal, "optimal"},
};
inline const char* to_string(Strategy value) { return name_in(kStrategyNames, value); }
inline constexpr EnumName<YawSource> kYawSourceNames[] = {
    {YawSource::kSetpoint, "setpoint"},
    {YawSource::kPid, "pid"},
};
inline const char* to_string(YawSource value) { return name_in(kYawSourceNames, value); }
inline constexpr EnumName<InputUnits> kInputUnitsNames[] = {
    {InputUnits::kNormalized, "normalized"},
    {InputUnits::kPhysical, "physical"},
};
inline const char* to_string(InputUnits value) { return name_in(kInputUnitsNames, value); }
inline constexpr EnumName<FailsafeAction> kFailsafeActionNames[] = {
    {FailsafeAction::kDisarm, "disarm"},
    {FailsafeAction::kHoldLast, "hold_last"},
    {FailsafeAction::kIdle, "idle"},
};
inline const char* to_string(FailsafeAction value) { return name_in(kFailsafeActionNames, value); }
inline constexpr EnumName<PublishMode> kPublishModeNames[] = {
    {PublishMode::kTimer, "timer"},
    {PublishMode::kOnInput, "on_input"},
};
inline const char* to_string(PublishMode value) { return name_in(kPublishModeNames, value); }

}  // namespace motormix::config
