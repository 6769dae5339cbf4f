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

void fill_kiss_message(int motor, const KissReading& r, std::int64_t utime,
                       motormix::esc_telemetry_t& msg) {
  msg = motormix::esc_telemetry_t{};
  msg.utime = utime;
  msg.count = 1;
  msg.motor = {static_cast<std::int8_t>(motor + 1)};
  msg.rpm = {std::numeric_limits<float>::quiet_NaN()};
  msg.erpm = {static_cast<float>(r.erpm)};
  msg.current_a = {static_cast<float>(r.current_a)};
  msg.voltage_v = {static_cast<float>(r.voltage_v)};
  msg.temperature_c = {static_cast<float>(r.temperature_c)};
  msg.consumption_mah = {static_cast<float>(r.consumption_mah)};
}

}  // namespace motormix::output
