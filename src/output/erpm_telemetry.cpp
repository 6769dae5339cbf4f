#include "output/erpm_telemetry.hpp"

#include "messages/esc_telemetry.hpp"

#include <cmath>
#include <limits>

namespace motormix::output {

bool fill_erpm_message(const PulseDriver::ErpmReading& reading, std::int64_t utime,
                       motormix::esc_telemetry_t& msg) {
  messages::start_esc_telemetry(msg, utime);
  for (std::size_t ch = 0; ch < reading.erpm.size(); ++ch) {
    const double erpm = reading.erpm[ch];
    if (!std::isfinite(erpm)) continue;  // no reply decoded: not named
    loop::EscReading r = messages::unknown_reading(static_cast<int>(ch) + 1);
    r.erpm = erpm;
    messages::add_esc_reading(msg, r);
  }
  return msg.count > 0;
}

void fill_kiss_message(int motor, const KissReading& k, std::int64_t utime,
                       motormix::esc_telemetry_t& msg) {
  messages::start_esc_telemetry(msg, utime);
  loop::EscReading r = messages::unknown_reading(motor + 1);  // rpm: the frame has eRPM only
  r.erpm = k.erpm;
  r.current_a = k.current_a;
  r.voltage_v = k.voltage_v;
  r.temperature_c = k.temperature_c;
  r.consumption_mah = k.consumption_mah;
  messages::add_esc_reading(msg, r);
}

}  // namespace motormix::output
