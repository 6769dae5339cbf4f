#pragma once
// esc_telemetry_t built one reading at a time, for every publisher of it
// (the output's bidirectional DShot and KISS readings, the simulator's ESCs,
// the PX4 import): its seven arrays grow together and its count follows
// them, so no publisher can send arrays of different lengths. A field an
// ESC does not report is NaN ("unknown" in esc_telemetry_t.lcm).

#include "loop/input_samples.hpp"

#include <motormix/esc_telemetry_t.hpp>

#include <cstdint>
#include <limits>

namespace motormix::messages {

inline constexpr double kUnknown = std::numeric_limits<double>::quiet_NaN();

// A reading of `motor` (1-based) with every field unknown: set those known.
inline loop::EscReading unknown_reading(int motor) {
  return loop::EscReading{motor, kUnknown, kUnknown, kUnknown, kUnknown, kUnknown, kUnknown};
}

// Empties `msg` (its arrays keep their storage) and stamps it.
void start_esc_telemetry(esc_telemetry_t& msg, std::int64_t utime);
// Appends one reading.
void add_esc_reading(esc_telemetry_t& msg, const loop::EscReading& reading);

}  // namespace motormix::messages
