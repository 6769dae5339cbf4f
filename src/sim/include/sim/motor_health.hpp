#pragma once
// The failures real motors have, as the simulator plays them, and what each
// motor can do at a given moment because of them.
//
//   stop          the motor stops at once (its rotor spins down with the
//                 motor lag)
//   half_thrust   the prop loses half its thrust; the motor keeps its speed
//   intermittent  the motor cuts out for 150 ms in every 500 ms
//   desync        the motor loses sync and spins down over 200 ms
//   telemetry     the ESC's telemetry dies; the motor keeps working
//   prop_lost     the propeller is thrown: no thrust, the unloaded motor
//                 speeds up toward its no-load speed (rpm x1.4 at the same
//                 command), its current falls away
//   prop_damaged  a broken blade tip: 45 % less thrust, the lighter-loaded
//                 motor turns faster than its command gives (rpm x1.12)

#include <motormix/enum_names.hpp>
#include <motormix/motor_vector.hpp>

#include <optional>
#include <string>

namespace motormix::sim {

enum class FailureKind {
  kStop,
  kHalfThrust,
  kIntermittent,
  kDesync,
  kTelemetry,
  kPropLost,
  kPropDamaged
};

inline constexpr EnumName<FailureKind> kFailureKindNames[] = {
    {FailureKind::kStop, "stop"},
    {FailureKind::kHalfThrust, "half_thrust"},
    {FailureKind::kIntermittent, "intermittent"},
    {FailureKind::kDesync, "desync"},
    {FailureKind::kTelemetry, "telemetry"},
    {FailureKind::kPropLost, "prop_lost"},
    {FailureKind::kPropDamaged, "prop_damaged"},
};
inline const char* to_string(FailureKind value) { return name_in(kFailureKindNames, value); }
std::optional<FailureKind> failure_kind(const std::string& name);

// Whether something outside motormix (an ESC driver, a health monitor) would
// report it on motor_status: a motor that stops, yes; a weak prop, a motor
// that comes and goes, a dead telemetry wire, no.
bool reported_outside(FailureKind kind);
// Whether the motor stops producing thrust (a detection of it is right).
bool loses_thrust(FailureKind kind);

struct MotorFailure {
  int motor = 0;  // 0-based
  double at_s = 0.0;
  FailureKind kind = FailureKind::kStop;
};

inline constexpr double kDesyncSpinDownS = 0.2;
inline constexpr double kIntermittentPeriodS = 0.5;
inline constexpr double kIntermittentOffS = 0.15;
// Unloaded, a motor's speed at a given command rises. A motor whose torque
// falls linearly from stall to its no-load speed w0 hovers near 0.75 w0:
// with no prop it runs at w0 (rpm x1.33); with a prop that lost 45 % of its
// thrust (and of its drag) it balances at 0.83 w0 (rpm x1.11). The factors
// below are on the thrust-fraction speed, rpm squared.
inline constexpr double kPropLostSpeedUp = (1.0 / 0.75) * (1.0 / 0.75);
inline constexpr double kPropDamagedSpeedUp = (0.831 / 0.75) * (0.831 / 0.75);
inline constexpr double kPropDamagedThrust = 0.55 / kPropDamagedSpeedUp;  // 45 % less thrust
// Without its prop a rotor is only the motor's bell: it follows its command
// this much faster (the bell is about a fifth of a 10-inch rotor's inertia).
inline constexpr double kPropLostLag = 0.2;

// Per motor, at one moment.
struct MotorHealth {
  MotorVector drive;  // factor on the speed the ESC drives (0: stopped)
  MotorVector prop;   // factor on the thrust at a given speed (0.5: half a prop)
  MotorVector lag;    // factor on the motor's time constants (1: with its prop)
  MotorMask telemetry_dead = 0;

  static MotorHealth healthy(int motors) {
    MotorHealth h;
    h.drive.setOnes(motors);
    h.prop.setOnes(motors);
    h.lag.setOnes(motors);
    return h;
  }
  // The failure's effect at time t (due: t >= at_s).
  void apply(const MotorFailure& f, double t);
};

}  // namespace motormix::sim
