#include "loop/message_checks.hpp"

#include <cmath>

namespace motormix::loop {

namespace {

bool in(double v, double lo, double hi) { return v >= lo && v <= hi; }

Rejection check_order(std::int64_t utime, std::int64_t last_utime) {
  if (utime >= last_utime) return Rejection::kNone;
  // In double: the difference of two arbitrary int64 values may overflow.
  const double behind = static_cast<double>(last_utime) - static_cast<double>(utime);
  return behind > static_cast<double>(kPublisherRestartUs) ? Rejection::kNone
                                                           : Rejection::kOutOfOrder;
}

}  // namespace

const char* to_string(Rejection rejection) {
  switch (rejection) {
    case Rejection::kNone:
      return "accepted";
    case Rejection::kNonFinite:
      return "non-finite field";
    case Rejection::kOutOfRange:
      return "field out of range";
    case Rejection::kOutOfOrder:
      return "utime went backwards";
    case Rejection::kFromFuture:
      return "utime in the future";
    case Rejection::kWrongSize:
      return "array size does not match the mixer";
  }
  return "?";
}

Rejection check_setpoint(const SetpointSample& s, ThrustRange thrust_range,
                         std::int64_t last_utime) {
  if (!std::isfinite(s.throttle) || !std::isfinite(s.yaw)) return Rejection::kNonFinite;
  const double throttle_low = thrust_floor(thrust_range);
  if (!in(s.throttle, throttle_low, 1.0) || !in(s.yaw, -1.0, 1.0)) return Rejection::kOutOfRange;
  return check_order(s.utime, last_utime);
}

Rejection check_pid(const PidSample& p, std::int64_t last_utime) {
  if (!std::isfinite(p.roll) || !std::isfinite(p.pitch) || !std::isfinite(p.yaw)) {
    return Rejection::kNonFinite;
  }
  if (!in(p.roll, -1.0, 1.0) || !in(p.pitch, -1.0, 1.0) || !in(p.yaw, -1.0, 1.0)) {
    return Rejection::kOutOfRange;
  }
  return check_order(p.utime, last_utime);
}

Rejection check_motor_status(const MotorStatusSample& m, int motors, std::int64_t last_utime) {
  if (m.num_motors != motors) return Rejection::kWrongSize;
  return check_order(m.utime, last_utime);
}

Rejection check_battery(const BatterySample& b, std::int64_t last_utime) {
  if (!std::isfinite(b.voltage)) return Rejection::kNonFinite;
  return check_order(b.utime, last_utime);
}

}  // namespace motormix::loop
