#include "node/messages.hpp"

namespace motormix::node {

void size_pwm_message(motor_pwm_t& msg, int motors) {
  msg.num_motors = motors;
  msg.command.assign(static_cast<std::size_t>(motors), 0.0F);
  msg.pwm.assign(static_cast<std::size_t>(motors), 0.0F);
  msg.direction.assign(static_cast<std::size_t>(motors), 0);
}

void fill_pwm_message(motor_pwm_t& msg, const CycleResult& r, std::int64_t utime) {
  msg.utime = utime;
  for (int i = 0; i < msg.num_motors; ++i) {
    const auto k = static_cast<std::size_t>(i);
    msg.command[k] = static_cast<float>(r.mix.command[i]);
    msg.pwm[k] = static_cast<float>(r.mix.output[i]);
    msg.direction[k] = r.mix.direction[k];
  }
  msg.armed = r.mix.armed;
  msg.setpoint_utime = r.setpoint_utime;
  msg.pid_utime = r.pid_utime;
}

void fill_status_message(mixer_status_t& s, const CycleResult& r, const Counters& c,
                         const LoopTiming& timing, std::uint64_t config_hash, int motors,
                         std::int64_t utime) {
  s.utime = utime;
  s.state = static_cast<int8_t>(r.state);
  s.failsafe_reason = static_cast<int8_t>(r.reason);
  s.setpoint_stale = r.setpoint_stale;
  s.pid_stale = r.pid_stale;
  s.num_motors = motors;
  const AllocationResult& a = r.last_armed_allocation;
  s.saturated_upper = static_cast<int32_t>(a.saturated_upper);
  s.saturated_lower = static_cast<int32_t>(a.saturated_lower);
  for (int i = 0; i < kNumAxes; ++i) {
    s.axis_limited[i] = (a.axis_limited >> i) & 1U;
    s.unallocated[i] = static_cast<float>(a.unallocated[i]);
  }
  s.cycles = c.cycles;
  s.setpoint_received = c.setpoint_received;
  s.pid_received = c.pid_received;
  s.rejected_decode = c.rejected_decode;
  s.rejected_nonfinite = c.rejected_nonfinite;
  s.rejected_range = c.rejected_range;
  s.rejected_stale_order = c.rejected_out_of_order;
  s.rejected_future = c.rejected_future;
  s.failsafe_events = c.failsafe_events;
  s.arming_refused = c.arming_refused;
  for (std::size_t i = 0; i < 4; ++i) {
    s.period_us[i] = timing.period_us[i];
    s.compute_us[i] = timing.compute_us[i];
  }
  s.overruns = timing.overruns;
  s.config_hash = static_cast<int64_t>(config_hash);
}

namespace {
template <typename Message>
bool decode_whole(const void* data, int size, Message& msg) {
  try {
    return msg.decode(data, 0, size) == size;
  } catch (...) {
    return false;
  }
}
}  // namespace

bool decode_setpoint(const void* data, int size, SetpointSample& out) {
  setpoint_t msg{};
  if (!decode_whole(data, size, msg)) return false;
  out = SetpointSample{msg.utime, msg.throttle, msg.yaw, msg.armed != 0};
  return true;
}

bool decode_pid(const void* data, int size, PidSample& out) {
  pid_t msg{};
  if (!decode_whole(data, size, msg)) return false;
  out = PidSample{msg.utime, msg.roll, msg.pitch, msg.yaw};
  return true;
}

}  // namespace motormix::node
