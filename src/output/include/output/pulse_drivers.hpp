#pragma once
// The pulse driver a configuration names (hardware.driver: serial or
// sysfs), opened and set up, and the pulse range of each output: what
// `motormix output` starts with and reopens a lost device with.

#include "output/output_gate.hpp"
#include "output/pulse_driver.hpp"

#include <motormix/config/config.hpp>

#include <memory>
#include <vector>

namespace motormix::output {

// Each output's range and disarmed value, in configured motor order.
std::vector<PulseRange> ranges_of(const config::Config& config);

// Throws (naming the device or the setting) when the hardware cannot be
// opened or set up.
std::unique_ptr<PulseDriver> make_driver(const config::Config& config);

}  // namespace motormix::output
