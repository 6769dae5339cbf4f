#pragma once
// What the ESCs report, onto the bus as esc_telemetry_t. Bidirectional
// DShot's eRPM: one message per DShot frame the firmware read replies after,
// naming the motors whose reply was decoded (a message need not name every
// motor), eRPM only: the failure detector turns it into rpm with the
// vehicle's pole pairs. A KISS frame: one message naming its wire's motor.

#include "output/kiss_telemetry.hpp"
#include "output/pulse_driver.hpp"

#include <motormix/esc_telemetry_t.hpp>

#include <cstdint>

namespace motormix::output {

// False when no motor's reply was decoded in that frame: nothing to send.
bool fill_erpm_message(const PulseDriver::ErpmReading& reading, std::int64_t utime,
                       motormix::esc_telemetry_t& msg);
// motor: 0-based. rpm is NaN (the frame carries eRPM only).
void fill_kiss_message(int motor, const KissReading& r, std::int64_t utime,
                       motormix::esc_telemetry_t& msg);

}  // namespace motormix::output
