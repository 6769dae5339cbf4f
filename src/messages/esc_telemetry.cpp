#include "messages/esc_telemetry.hpp"

#include "bus/wire_shape.hpp"

namespace motormix::messages {

void start_esc_telemetry(esc_telemetry_t& msg, std::int64_t utime) {
  msg.utime = utime;
  // Its arrays as the wire's sizing names them (empty: readings follow).
  bus::WireShape<esc_telemetry_t>::size(msg, 0);
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
