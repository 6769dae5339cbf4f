#pragma once
// One simulated run in lockstep: the scenario, the built-in controller, the
// real control loop (loop::ControlLoop: arming, staleness, battery
// compensation, motor_status handling) around the real Mixer and output
// stage, and the vehicle model, all on the simulated clock. Nothing waits
// on a wall clock, so a run is as fast as the CPU and the same inputs and
// seed give the same results, bit for bit.
//
// Each loop period: the scenario's events due are applied; the controller
// reads the (noisy) state and sends a setpoint and a pid; a battery reading
// (50 Hz) and a motor_status (from the failure's detection on, 10 Hz) are
// delivered when due; the control loop cycles; the vehicle integrates the
// outputs over the period in steps of at most 1 ms.

#include "loop/control_loop.hpp"
#include "sim/controller.hpp"
#include "sim/realism.hpp"
#include "sim/scenario.hpp"
#include "sim/scenario_clock.hpp"
#include "sim/scoring.hpp"
#include "sim/sensors.hpp"
#include "sim/vehicle_model.hpp"

#include <motormix/config/config.hpp>
#include <motormix/mixer.hpp>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace motormix::sim {

inline constexpr std::int64_t kEpochUs = 1700000000000000;  // utime of simulated time 0

struct SimOptions {
  std::vector<MotorFailure> failures;  // on top of the scenario's
  bool undetected = false;             // never report the failures on motor_status
  std::uint64_t seed = 1;
  double duration_s = 0.0;  // > 0: instead of the scenario's
  Realism realism;          // what of the real world is played (realism.hpp)
};

// Everything one loop period produced, for logs and plots.
struct SimFrame {
  std::int64_t utime = 0;
  const loop::SetpointSample* setpoint = nullptr;
  const loop::PidSample* pid = nullptr;
  const loop::CycleResult* cycle = nullptr;
  const VehicleModel* vehicle = nullptr;
  const loop::BatterySample* battery = nullptr;           // when one was sent this period
  const loop::MotorStatusSample* motor_status = nullptr;  // when one was sent this period
  const Reference* reference = nullptr;
  const ControllerCommand* command = nullptr;  // what the controller sent
  const loop::Counters* counters = nullptr;
};
using FrameObserver = std::function<void(const SimFrame&)>;

// The configuration as the scenario flies it: its battery settings and the
// realism's switches applied (what the controller and motormix see).
// Throws config::ConfigError when the scenario is for the other kind of
// vehicle.
config::Config scenario_config(const config::Config& config, const Scenario& scenario,
                               const Realism& realism = {});

// `mixer` is what the control loop flies with (build_mixer(config), or a
// comparison allocator); the controller linearizes it.
SimResult run_lockstep(const config::Config& config, Mixer mixer, const Scenario& scenario,
                       const SimOptions& options, const FrameObserver& observer = {});

}  // namespace motormix::sim
