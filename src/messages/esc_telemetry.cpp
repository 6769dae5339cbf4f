#include "messages/esc_telemetry.hpp"

namespace motormix::messages {

void start_esc_telemetry(esc_telemetry_t& msg, std::int64_t utime) {
  msg.utime = utime;
  msg.count = 0;
  msg.motor.clear();
  for (auto* v : {&msg.rpm, &msg.erpm, &msg.current_a, &msg.voltage_v, &msg.temperature_c,
                  &msg.consumption_mah})
    v->clear();
}

void add_esc_reading(esc_telemetry_t& msg, const loop::EscReading& r) {
  msg.motor.push_back(static_cast<std::int8_t>(r.motor));
  msg.rpm.push_back(static_cast<float>(r.rpm));
  msg.erpm.push_back(static_cast<float>(r.erpm));
  msg.current_a.push_back(static_cast<float>(r.current_a));
  msg.voltage_v.push_back(static_cast<float>(r.voltage_v));
  msg.temperature_c.push_back(static_cast<float>(r.temperature_c));
  msg.consumption_mah.push_back(static_cast<float>(r.consumption_mah));
  msg.count = static_cast<std::int32_t>(msg.motor.size());
}

}  // namespace motormix::messages
