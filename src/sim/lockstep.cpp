#include "sim/lockstep.hpp"

#include "sim/period.hpp"
#include "sim/plant.hpp"

#include <motormix/angles.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace motormix::sim {

namespace {

std::int64_t to_us(double s) { return static_cast<std::int64_t>(std::llround(s * 1e6)); }

}  // namespace

config::Config scenario_config(const config::Config& config_in, const Scenario& scenario,
                               const Realism& realism) {
  const bool wheeled = config_in.thrust_range() == ThrustRange::kBipolar;
  if (scenario.vehicle == ScenarioVehicle::kAircraft && wheeled) {
    throw config::ConfigError("scenario " + scenario.name + " is for aircraft, and " +
                              config_in.name + " is a ground vehicle");
  }
  if (scenario.vehicle == ScenarioVehicle::kGround && !wheeled) {
    throw config::ConfigError("scenario " + scenario.name + " is for ground vehicles, and " +
                              config_in.name + " is an aircraft");
  }
  config::Config config = config_in;
  if (scenario.battery_initial_charge)
    config.vehicle_model.battery.initial_charge = *scenario.battery_initial_charge;
  if (scenario.battery_resistance_factor)
    config.vehicle_model.battery.internal_resistance_ohm *= *scenario.battery_resistance_factor;
  apply_realism(config, realism);
  return config;
}

SimResult run_lockstep(const config::Config& config_in, Mixer mixer, const Scenario& scenario,
                       const SimOptions& options, const FrameObserver& observer) {
  const auto wall_start = std::chrono::steady_clock::now();
  const bool wheeled = config_in.thrust_range() == ThrustRange::kBipolar;
  const config::Config config = scenario_config(config_in, scenario, options.realism);
  Plant plant(config, scenario, options.realism, options.seed);
  const VehicleModel& vehicle = plant.vehicle();
  loop::ControlLoop loop(config, std::move(mixer));
  Controller controller = Controller::for_vehicle(config, loop.mixer(), vehicle);
  ScenarioClock clock(scenario, config, options.failures);
  DetectionScorer detections(clock.failures());

  const SimulationPeriod periods(config.loop_rate_hz,
                                 options.duration_s > 0 ? options.duration_s : scenario.duration_s,
                                 options.realism.imu ? config.vehicle_model.imu.rate_hz : 0.0);
  const double period = periods.period_s;
  MessageSchedule schedule;

  SimResult r;
  r.min_battery_v = vehicle.battery().terminal_v();
  Scorer scorer(scenario, config);
  if (!clock.failures().empty()) scorer.failure_at(clock.failures().front().at_s);
  bool mixer_armed = false;
  AxisVector unallocated = AxisVector::Zero();
  loop::SetpointSample setpoint;
  loop::PidSample pid;
  loop::BatterySample battery;
  loop::MotorStatusSample motor_status;

  for (std::int64_t k = 0; k < periods.cycles; ++k) {
    const double t = periods.start_of(k);
    const std::int64_t now = kEpochUs + to_us(t);
    clock.advance(t);
    const Reference& ref = clock.reference();

    const ControllerCommand cmd =
        controller.update(ref, plant.measured(), plant.measured_speed(), mixer_armed,
                          vehicle.landed() && !wheeled, unallocated, period);
    setpoint = {now, cmd.thrust, cmd.yaw, cmd.armed};
    pid = {now, cmd.roll, cmd.pitch, cmd.yaw};
    loop.on_setpoint(setpoint, now, now);
    loop.on_pid(pid, now, now);

    const bool battery_sent = schedule.battery_due(t);
    if (battery_sent) {
      battery = {now, vehicle.battery().terminal_v()};
      loop.on_battery(battery, now, now);
    }
    const MotorHealth& health = clock.health(t);
    if (loop.reads_esc_telemetry()) {
      const loop::EscTelemetrySample& esc = plant.esc_telemetry(t, now, health);
      if (esc.count > 0) loop.on_esc_telemetry(esc, now, now);
    }
    if (loop.reads_attitude()) loop.on_attitude(plant.attitude(now), now, now);
    const MotorMask detected =
        options.undetected ? 0 : clock.detected(t, scenario.failure_detection_s);
    const bool status_sent = schedule.motor_status_due(t, detected);
    if (status_sent) {
      motor_status = {now, config.motors(), detected};
      loop.on_motor_status(motor_status, now, now);
    }

    const loop::CycleResult& cycle = loop.cycle(now);
    mixer_armed = cycle.state == loop::LoopState::kArmed;
    unallocated = mixer_armed ? cycle.mix.allocation.unallocated : AxisVector::Zero();
    if (observer) {
      SimFrame f;
      f.utime = now;
      f.setpoint = &setpoint;
      f.pid = &pid;
      f.cycle = &cycle;
      f.vehicle = &vehicle;
      f.battery = battery_sent ? &battery : nullptr;
      f.motor_status = status_sent ? &motor_status : nullptr;
      f.reference = &ref;
      f.command = &cmd;
      f.counters = &loop.counters();
      observer(f);
    }

    scorer.add(t, ref, cmd, vehicle, mixer_armed, cycle.mix.allocation.axis_limited);
    detections.add(t, cycle, vehicle);

    plant.integrate(periods, cycle.mix.output, cycle.mix.direction, health, clock, t);
    if (end_of_period(r, vehicle, k, t + period)) break;
  }
  scorer.finish(r);
  detections.finish(r);
  r.failsafe_events = loop.counters().failsafe_events;
  r.final_charge = vehicle.battery().charge();
  r.sim_seconds = static_cast<double>(r.cycles) * period;
  r.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return r;
}

}  // namespace motormix::sim
