#pragma once
// Bidirectional DShot's eRPM onto the bus: one esc_telemetry_t per DShot
// frame the firmware read replies after, naming the motors whose reply was
// decoded (a message need not name every motor), eRPM only: the failure
// detector turns it into rpm with the vehicle's pole pairs.

#include "output/pulse_driver.hpp"

#include <motormix/esc_telemetry_t.hpp>

#include <cstdint>

namespace motormix::output {

// False when no motor's reply was decoded in that frame: nothing to send.
bool fill_erpm_message(const PulseDriver::ErpmReading& reading, std::int64_t utime,
                       motormix::esc_telemetry_t& msg);

}  // namespace motormix::output
