#pragma once
// Where a motormix message keeps its array length on the wire, so that the
// length can be checked against the bytes received before LCM's decoder
// sizes a vector from it. lcm-gen's decoders resize every array to the
// length they read before checking that the bytes are there: a length of -1
// throws std::length_error, one of 2^31-1 allocates gigabytes. Each message
// type motormix reads has at most one length field, at a fixed offset
// (everything before it has a fixed size); a type with none has one size.
//
// Only the offset, the largest length and how to size the arrays are
// written here; the fixed part and the bytes per element are measured from
// the generated encoder itself (receive.hpp), and a unit test checks each
// offset against an encoded message.

#include <motormix/attitude_t.hpp>
#include <motormix/battery_t.hpp>
#include <motormix/esc_telemetry_t.hpp>
#include <motormix/mixer_status_t.hpp>
#include <motormix/motor_pwm_t.hpp>
#include <motormix/motor_status_t.hpp>
#include <motormix/motor_test_t.hpp>
#include <motormix/motor_vector.hpp>
#include <motormix/pid_t.hpp>
#include <motormix/setpoint_t.hpp>
#include <motormix/vehicle_state_t.hpp>

#include <cstddef>

namespace motormix::bus {

// A type without arrays: one size, no length to check.
template <typename Message>
struct WireShape {
  static constexpr bool kHasLength = false;
};

// The offsets count the 8-byte fingerprint: they index the received bytes.
template <>
struct WireShape<motor_pwm_t> {
  static constexpr bool kHasLength = true;
  static constexpr int kLengthOffset = 16;  // fingerprint, utime
  static constexpr int kMaxLength = kMaxMotors;
  static void size(motor_pwm_t& m, int n) {
    const auto k = static_cast<std::size_t>(n);
    m.num_motors = n;
    m.command.assign(k, 0.0F);
    m.pwm.assign(k, 0.0F);
    m.direction.assign(k, 0);
  }
};

template <>
struct WireShape<motor_status_t> {
  static constexpr bool kHasLength = true;
  static constexpr int kLengthOffset = 16;  // fingerprint, utime
  static constexpr int kMaxLength = kMaxMotors;
  static void size(motor_status_t& m, int n) {
    m.num_motors = n;
    m.failed.assign(static_cast<std::size_t>(n), 0);
  }
};

template <>
struct WireShape<esc_telemetry_t> {
  static constexpr bool kHasLength = true;
  static constexpr int kLengthOffset = 16;  // fingerprint, utime
  static constexpr int kMaxLength = 16;     // esc_telemetry_t.lcm: 1..16 readings
  static void size(esc_telemetry_t& m, int n) {
    const auto k = static_cast<std::size_t>(n);
    m.count = n;
    m.motor.assign(k, 0);
    for (auto* v :
         {&m.rpm, &m.erpm, &m.current_a, &m.voltage_v, &m.temperature_c, &m.consumption_mah})
      v->assign(k, 0.0F);
  }
};

template <>
struct WireShape<vehicle_state_t> {
  static constexpr bool kHasLength = true;
  // fingerprint, utime, position[3], velocity[3], q[4], rates[3] (doubles)
  static constexpr int kLengthOffset = 8 + 8 + 8 * (3 + 3 + 4 + 3);
  static constexpr int kMaxLength = kMaxMotors;
  static void size(vehicle_state_t& m, int n) {
    const auto k = static_cast<std::size_t>(n);
    m.num_motors = n;
    m.thrust.assign(k, 0.0F);
    m.motor_speed.assign(k, 0.0F);
  }
};

}  // namespace motormix::bus
