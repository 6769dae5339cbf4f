#include "sim/bus/sim_log.hpp"

#include <cmath>

namespace motormix::sim {

void fill_vehicle_state(vehicle_state_t& msg, const VehicleModel& vehicle, std::int64_t utime) {
  const BodyState& b = vehicle.body();
  msg.utime = utime;
  for (int i = 0; i < 3; ++i) {
    msg.position[i] = b.position[i];
    msg.velocity[i] = b.velocity[i];
    msg.rates[i] = b.rates[i];
  }
  msg.q[0] = b.attitude.w();
  msg.q[1] = b.attitude.x();
  msg.q[2] = b.attitude.y();
  msg.q[3] = b.attitude.z();
  msg.num_motors = vehicle.motors();
  msg.thrust.resize(static_cast<std::size_t>(vehicle.motors()));
  msg.motor_speed.resize(static_cast<std::size_t>(vehicle.motors()));
  for (int i = 0; i < vehicle.motors(); ++i) {
    msg.thrust[static_cast<std::size_t>(i)] = static_cast<float>(vehicle.thrust_n(i));
    msg.motor_speed[static_cast<std::size_t>(i)] = static_cast<float>(vehicle.motor_speed(i));
  }
  msg.battery_v = static_cast<float>(vehicle.battery().terminal_v());
  msg.landed = vehicle.landed();
  msg.crashed = vehicle.crashed();
}

SimLogWriter::SimLogWriter(const std::string& path, const config::Config& config)
    : log_(path), config_(config) {
  messages::size_pwm_message(pwm_, config.motors());
}

void SimLogWriter::write(const SimFrame& f, const loop::Counters& counters) {
  const config::Channels& ch = config_.channels;
  setpoint_t sp;
  sp.utime = f.setpoint->utime;
  sp.throttle = static_cast<float>(f.setpoint->throttle);
  sp.yaw = static_cast<float>(f.setpoint->yaw);
  sp.armed = f.setpoint->armed;
  log_.write(ch.setpoint, f.utime, sp);
  pid_t pid;
  pid.utime = f.pid->utime;
  pid.roll = static_cast<float>(f.pid->roll);
  pid.pitch = static_cast<float>(f.pid->pitch);
  pid.yaw = static_cast<float>(f.pid->yaw);
  log_.write(ch.pid, f.utime, pid);
  if (f.battery != nullptr) {
    battery_t b;
    b.utime = f.battery->utime;
    b.voltage = static_cast<float>(f.battery->voltage);
    log_.write(ch.battery, f.utime, b);
  }
  if (f.motor_status != nullptr) {
    motor_status_t m;
    m.utime = f.motor_status->utime;
    m.num_motors = f.motor_status->num_motors;
    for (int i = 0; i < m.num_motors; ++i) m.failed.push_back((f.motor_status->failed >> i) & 1U);
    log_.write(ch.motor_status, f.utime, m);
  }
  messages::fill_pwm_message(pwm_, *f.cycle, f.utime);
  log_.write(ch.motor_pwm, f.utime, pwm_);
  if (f.utime >= next_status_us_) {
    messages::fill_status_message(status_, *f.cycle, counters, messages::LoopTiming{}, config_.hash,
                                  config_.motors(), f.utime);
    log_.write(ch.status, f.utime, status_);
    next_status_us_ =
        f.utime + static_cast<std::int64_t>(std::llround(1e6 / config_.status_rate_hz));
  }
  fill_vehicle_state(state_, *f.vehicle, f.utime);
  log_.write(kVehicleStateChannel, f.utime, state_);
}

}  // namespace motormix::sim
