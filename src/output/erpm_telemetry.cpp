#include "output/erpm_telemetry.hpp"

#include <cmath>
#include <limits>

namespace motormix::output {

bool fill_erpm_message(const PulseDriver::ErpmReading& reading, std::int64_t utime,
                       motormix::esc_telemetry_t& msg) {
  constexpr float kUnknown = std::numeric_limits<float>::quiet_NaN();
  msg = motormix::esc_telemetry_t{};
  msg.utime = utime;
  for (std::size_t ch = 0; ch < reading.erpm.size(); ++ch) {
    const double erpm = reading.erpm[ch];
    if (!std::isfinite(erpm)) continue;  // no reply decoded: not named
    msg.motor.push_back(static_cast<std::int8_t>(ch + 1));
    msg.rpm.push_back(kUnknown);
    msg.erpm.push_back(static_cast<float>(erpm));
    msg.current_a.push_back(kUnknown);
    msg.voltage_v.push_back(kUnknown);
    msg.temperature_c.push_back(kUnknown);
    msg.consumption_mah.push_back(kUnknown);
  }
  msg.count = static_cast<std::int32_t>(msg.motor.size());
  return msg.count > 0;
}

}  // namespace motormix::output
