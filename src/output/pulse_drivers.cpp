#include "output/pulse_drivers.hpp"

#include "output/serial_port.hpp"
#include "output/serial_pulse_driver.hpp"
#include "output/sysfs_pwm_driver.hpp"

#include <algorithm>
#include <cstdint>
#include <limits>

namespace motormix::output {

std::vector<PulseRange> ranges_of(const config::Config& config) {
  std::vector<PulseRange> out;
  for (const OutputChannel& ch : config.outputs) {
    out.push_back({std::min(ch.min, ch.max), std::max(ch.min, ch.max), ch.disarmed});
  }
  return out;
}

std::unique_ptr<PulseDriver> make_driver(const config::Config& config) {
  const config::Hardware& hw = config.hardware;
  const double period_us = 1e6 / hw.pulse_rate_hz;
  std::vector<double> disarmed;
  double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
  for (const PulseRange& r : ranges_of(config)) {
    disarmed.push_back(r.disarmed);
    lo = std::min(lo, r.low);
    hi = std::max(hi, r.high);
  }
  if (hw.driver == config::HardwareDriver::kSerial) {
    SerialPulseSettings s;
    s.period_us = period_us;
    s.link_timeout_ms = hw.serial.link_timeout_s * 1e3;
    s.min_us = lo;
    s.max_us = hi;
    s.disarmed_us = disarmed;
    s.protocol = static_cast<std::uint8_t>(hw.protocol);  // enum order is the link's
    s.bidirectional = hw.bidirectional;
    s.baud = hw.serial.baud;
    return std::make_unique<SerialPulseDriver>(open_serial_port(hw.serial.device, hw.serial.baud),
                                               s);
  }
  return std::make_unique<SysfsPwmDriver>(hw.sysfs, period_us, disarmed);
}

}  // namespace motormix::output
