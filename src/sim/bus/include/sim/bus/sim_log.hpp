#pragma once
// A lockstep run as a normal LCM event log: the controller's setpoint and
// pid, motor_pwm_t and mixer_status_t exactly as `motormix run` publishes
// them, battery_t, motor_status_t and vehicle_state_t, each on its
// configured channel (VEHICLE_STATE for the state) with the simulated time
// as the event time. lcm-logplayer, `motormix replay` and the plot tool
// read it.

#include "messages/log_writer.hpp"
#include "messages/messages.hpp"
#include "sim/lockstep.hpp"

#include <motormix/vehicle_state_t.hpp>

#include <string>

namespace motormix::sim {

inline constexpr const char* kVehicleStateChannel = "VEHICLE_STATE";

// Fills a vehicle_state_t from the model.
void fill_vehicle_state(vehicle_state_t& msg, const VehicleModel& vehicle, std::int64_t utime);

class SimLogWriter {
 public:
  SimLogWriter(const std::string& path, const config::Config& config);
  bool good() const { return log_.good(); }
  void write(const SimFrame& frame, const loop::Counters& counters);
  // False if anything could not be written (disk full, I/O error).
  bool close() { return log_.close(); }

 private:
  messages::LogWriter log_;
  const config::Config& config_;
  std::int64_t next_status_us_ = 0;
  motor_pwm_t pwm_;
  mixer_status_t status_;
  vehicle_state_t state_;
};

}  // namespace motormix::sim
