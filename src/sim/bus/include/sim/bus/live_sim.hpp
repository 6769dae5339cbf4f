#pragma once
// `motormix sim --lcm`: the simulated vehicle on a real bus, in real time,
// beside a separate `motormix run` (software in the loop). It takes
// motor_pwm_t from the mixer and publishes vehicle_state_t, battery_t,
// motor_status_t and, unless the controller is off, the controller's
// setpoint_t and pid_t, on the configuration's channels. Motor outputs older
// than the mixer's input timeout, or none yet, count as disarmed (the ESCs
// stop). The run is bounded by the scenario's duration or `duration_s`.
// With security.mode sign or require, everything it publishes is signed, as
// link security.link_id + 128 (it publishes motor_status_t as the mixer
// does), and what it reads from the mixer must verify as the mode says.

#include "bus/receive.hpp"
#include "sim/lockstep.hpp"

#include <iosfwd>
#include <string>

namespace motormix::sim {

struct LiveOptions {
  SimOptions sim;
  std::string lcm_url;     // empty: LCM's default ($LCM_DEFAULT_URL)
  bool controller = true;  // false: a controller of the user's flies from VEHICLE_STATE
  // Drive `motormix run --lockstep` tick by tick (docs/lockstep.md): after
  // each cycle's messages a lockstep_t at the simulated time, then wait for
  // the mixer's motor_pwm_t stamped with it. As fast as both sides go, the
  // same whatever the machine's load; times on the bus are simulated
  // (from sim::kEpochUs).
  bool lockstep = false;
};

struct LiveResult {
  SimResult sim;
  std::int64_t pwm_received = 0;       // motor_pwm_t accepted from the mixer
  std::int64_t pwm_rejected = 0;       // refused by the bus's guard, wrong size or not finite
  std::int64_t statuses_received = 0;  // mixer_status_t (its unallocated demand feeds anti-windup)
  bus::Refusals refused;               // on both channels, by reason (bus::receive)
  bool interrupted = false;            // SIGTERM / SIGINT / SIGHUP ended the flight early
  bool lockstep_lost = false;          // lockstep: the mixer did not answer a tick (5 s)
  bool bus_ok = true;
};

// Returns false with a message on `err` when the bus cannot be opened.
bool run_live(const config::Config& config, const Scenario& scenario, const LiveOptions& options,
              LiveResult& result, std::ostream& err);

}  // namespace motormix::sim
