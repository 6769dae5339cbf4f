#include "loop/message_checks.hpp"

#include <cmath>
#include <iterator>
#include <utility>

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

namespace {

// NaN: not reported, accepted. Infinite: a broken encoder, rejected.
Rejection check_optional(double v, double lo, double hi) {
  if (std::isnan(v)) return Rejection::kNone;
  if (!std::isfinite(v)) return Rejection::kNonFinite;
  return in(v, lo, hi) ? Rejection::kNone : Rejection::kOutOfRange;
}

// The documented ranges of esc_telemetry_t, wide enough for any real ESC.
constexpr double kMaxRpm = 1e6;
constexpr double kMinCurrentA = -50.0, kMaxCurrentA = 1000.0;
constexpr double kMaxVoltageV = 100.0;
constexpr double kMinTemperatureC = -60.0, kMaxTemperatureC = 250.0;
constexpr double kMaxConsumptionMah = 1e7;
// A quaternion this far from unit length is not an attitude.
constexpr double kUnitTolerance = 0.01;

}  // namespace

EscTelemetryVerdict check_esc_telemetry(
    const EscTelemetrySample& t, int motors,
    const std::array<std::int64_t, kMaxEscReadings>& last_utime) {
  EscTelemetryVerdict v;
  if (t.count < 1 || t.count > kMaxEscReadings) {
    v.message = Rejection::kWrongSize;
    return v;
  }
  const std::pair<double, double> ranges[] = {{0.0, kMaxRpm},
                                              {0.0, kMaxRpm},
                                              {kMinCurrentA, kMaxCurrentA},
                                              {0.0, kMaxVoltageV},
                                              {kMinTemperatureC, kMaxTemperatureC},
                                              {0.0, kMaxConsumptionMah}};
  for (int i = 0; i < t.count; ++i) {
    const EscReading& r = t.readings[static_cast<std::size_t>(i)];
    Rejection& verdict = v.reading[static_cast<std::size_t>(i)];
    if (r.motor < 1 || r.motor > motors) {
      verdict = Rejection::kOutOfRange;  // no such motor
    } else {
      const double values[] = {r.rpm,       r.erpm,          r.current_a,
                               r.voltage_v, r.temperature_c, r.consumption_mah};
      for (std::size_t k = 0; k < std::size(values) && verdict == Rejection::kNone; ++k) {
        verdict = check_optional(values[k], ranges[k].first, ranges[k].second);
      }
      if (verdict == Rejection::kNone) {
        verdict = check_order(t.utime, last_utime[static_cast<std::size_t>(r.motor - 1)]);
      }
    }
    if (verdict == Rejection::kNone) {
      v.taken |= 1U << i;
    } else {
      ++v.refused;
    }
  }
  return v;
}

namespace {

// A vector that is all known or all NaN (unknown): none infinite, no half
// of one, each known component within +-limit. `known`: whether it is.
template <std::size_t N>
Rejection known_or_unknown(const std::array<double, N>& v, double limit, bool& known) {
  std::size_t unknown = 0;
  for (double c : v) {
    if (std::isnan(c)) {
      ++unknown;
    } else if (!std::isfinite(c)) {
      return Rejection::kNonFinite;
    } else if (std::abs(c) > limit) {
      return Rejection::kOutOfRange;
    }
  }
  known = unknown == 0;
  return unknown == 0 || unknown == N ? Rejection::kNone : Rejection::kNonFinite;
}

}  // namespace

Rejection check_attitude(const AttitudeSample& a, std::int64_t last_utime) {
  for (double w : a.rates) {
    if (!std::isfinite(w)) return Rejection::kNonFinite;
    if (std::abs(w) > kMaxBodyRateRadS) return Rejection::kOutOfRange;
  }
  bool known = false;
  Rejection r = known_or_unknown(a.q, 1.0 + kUnitTolerance, known);
  if (r != Rejection::kNone) return r;
  if (known) {
    double norm_sq = 0.0;
    for (double c : a.q) norm_sq += c * c;
    if (std::abs(std::sqrt(norm_sq) - 1.0) > kUnitTolerance) return Rejection::kOutOfRange;
  }
  // Velocity: no faster than any multirotor flies.
  r = known_or_unknown(a.velocity, kMaxVelocityMps, known);
  if (r != Rejection::kNone) return r;
  return check_order(a.utime, last_utime);
}

}  // namespace motormix::loop
