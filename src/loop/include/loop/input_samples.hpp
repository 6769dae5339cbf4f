#pragma once
// Decoded, not yet validated input messages, free of LCM types so the control
// loop can be driven from a bus, a log file or a test alike.

#include <array>
#include <cstdint>
#include <limits>

namespace motormix::loop {

struct SetpointSample {
  std::int64_t utime = 0;  // publisher's timestamp, microseconds
  double throttle = 0.0;
  double yaw = 0.0;
  bool armed = false;
};

struct PidSample {
  std::int64_t utime = 0;
  double roll = 0.0;
  double pitch = 0.0;
  double yaw = 0.0;
};

struct MotorStatusSample {
  std::int64_t utime = 0;
  int num_motors = 0;        // as sent; must match the mixer
  std::uint32_t failed = 0;  // bit i: failed[i] was true
};

struct BatterySample {
  std::int64_t utime = 0;
  double voltage = 0.0;
};

struct MotorTestSample {
  std::int64_t utime = 0;
  int motor = 0;  // 1-based; 0 stops the test in progress
  double throttle = 0.0;
  double duration_s = 0.0;
};

// One ESC's reading in an esc_telemetry message; NaN: not reported.
struct EscReading {
  int motor = 0;  // 1-based, as sent
  double rpm = 0.0;
  double erpm = 0.0;
  double current_a = 0.0;
  double voltage_v = 0.0;
  double temperature_c = 0.0;
  double consumption_mah = 0.0;
};

inline constexpr int kMaxEscReadings = 16;  // readings in one esc_telemetry message

struct EscTelemetrySample {
  std::int64_t utime = 0;
  int count = 0;  // as sent; 1..kMaxEscReadings, else rejected
  std::array<EscReading, kMaxEscReadings> readings{};
};

struct AttitudeSample {
  static constexpr double kUnknown = std::numeric_limits<double>::quiet_NaN();
  std::int64_t utime = 0;
  std::array<double, 4> q{1.0, 0.0, 0.0, 0.0};  // w, x, y, z; all NaN: attitude unknown
  std::array<double, 3> rates{};                // rad/s, body FRD
  // m/s NED; all NaN: unknown (the spin landing then follows the throttle).
  std::array<double, 3> velocity{kUnknown, kUnknown, kUnknown};
};

}  // namespace motormix::loop
