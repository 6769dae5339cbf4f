#pragma once
// Acceptance rules for input messages. A message is either accepted whole or
// rejected with one reason, which the control loop counts; the one
// exception is esc_telemetry, whose readings are judged one by one (a bad
// reading costs that reading, not the other ESCs' in the same message).

#include <motormix/enum_names.hpp>
#include "loop/input_samples.hpp"

#include <motormix/mixer.hpp>

#include <array>
#include <cstdint>

namespace motormix::loop {

enum class Rejection : std::uint8_t {
  kNone = 0,
  kNonFinite,   // a NaN or infinite field
  kOutOfRange,  // a field outside its documented range
  kOutOfOrder,  // utime went backwards on this channel
  kFromFuture,  // utime further ahead of this host's clock than inputs.max_future_ms
  kWrongSize,   // an array whose length does not match the mixer (motor_status num_motors)
};

inline constexpr EnumName<Rejection> kRejectionNames[] = {
    {Rejection::kNone, "accepted"},
    {Rejection::kNonFinite, "non-finite field"},
    {Rejection::kOutOfRange, "field out of range"},
    {Rejection::kOutOfOrder, "utime went backwards"},
    {Rejection::kFromFuture, "utime in the future"},
    {Rejection::kWrongSize, "array size does not match the mixer"},
};
inline const char* to_string(Rejection value) { return name_in(kRejectionNames, value); }

// A utime this far behind the last accepted one is taken as a restarted
// publisher (its clock reset), not a reordered message.
inline constexpr std::int64_t kPublisherRestartUs = 1'000'000;

Rejection check_setpoint(const SetpointSample& s, ThrustRange thrust_range,
                         std::int64_t last_utime);
Rejection check_pid(const PidSample& p, std::int64_t last_utime);
Rejection check_motor_status(const MotorStatusSample& m, int motors, std::int64_t last_utime);
// Only the order: the voltage's plausibility is the battery compensation's.
Rejection check_battery(const BatterySample& b, std::int64_t last_utime);
// What check_esc_telemetry says of one message: `message` is kWrongSize
// when its count is outside 1..kMaxEscReadings (nothing in it is read);
// otherwise each reading has its own verdict, and `taken` has bit i set for
// each reading i accepted.
struct EscTelemetryVerdict {
  Rejection message = Rejection::kNone;
  std::array<Rejection, kMaxEscReadings> reading{};
  std::uint32_t taken = 0;
  int refused = 0;  // readings refused (message accepted)
};
// Each reading alone: a motor the mixer has, fields in their documented
// ranges, and in order for that motor (ESCs report at their own rates,
// possibly through several publishers; last_utime[i]: the last accepted
// reading of motor i, kNever if none). A publisher may batch: several
// readings of one motor in one message are taken in order (the last is the
// newest), and a message may hold more readings than there are motors.
EscTelemetryVerdict check_esc_telemetry(
    const EscTelemetrySample& t, int motors,
    const std::array<std::int64_t, kMaxEscReadings>& last_utime);
// Largest body rate accepted: twice the 2000 deg/s range of common gyros.
inline constexpr double kMaxBodyRateRadS = 70.0;
// The largest velocity component an attitude message may carry (m/s).
inline constexpr double kMaxVelocityMps = 150.0;
Rejection check_attitude(const AttitudeSample& a, std::int64_t last_utime);

}  // namespace motormix::loop
