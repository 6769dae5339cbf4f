#include "sim/lockstep.hpp"

#include "sim/attitude_sensor.hpp"
#include "sim/esc_telemetry_model.hpp"
#include "sim/period.hpp"

#include <motormix/angles.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace motormix::sim {

namespace {

constexpr double kReachedM = 0.1;            // within this of the commanded altitude: arrived

double wrap(double angle) { return std::remainder(angle, 2 * kPi); }

std::int64_t to_us(double s) { return static_cast<std::int64_t>(std::llround(s * 1e6)); }

}  // namespace

ScenarioClock::ScenarioClock(const Scenario& scenario, const config::Config& config,
                             const std::vector<MotorFailure>& extra_failures)
    : scenario_(scenario) {
  for (const ScenarioEvent& e : scenario.timeline) {
    if (e.fail) failures_.push_back({*e.fail, e.at_s, e.fail_kind});
  }
  for (const MotorFailure& f : extra_failures) failures_.push_back(f);
  std::stable_sort(failures_.begin(), failures_.end(),
                   [](const MotorFailure& a, const MotorFailure& b) { return a.at_s < b.at_s; });
  for (const MotorFailure& f : failures_) {
    if (f.motor < 0 || f.motor >= config.motors()) {
      throw config::ConfigError("motor " + std::to_string(f.motor + 1) +
                                " to fail: the vehicle has motors 1 to " +
                                std::to_string(config.motors()));
    }
  }
  ref_.armed = false;
  ref_.altitude_m = scenario.altitude_m;
  health_ = MotorHealth::healthy(config.motors());
}

const MotorHealth& ScenarioClock::health(double t) {
  health_.drive.setOnes();
  health_.prop.setOnes();
  health_.telemetry_dead = 0;
  for (const MotorFailure& f : failures_) {
    if (f.at_s > t) break;  // as the timeline's events: due once t reaches them
    health_.apply(f, t);
  }
  return health_;
}

void ScenarioClock::advance(double t) {
  ref_.armed = t >= scenario_.arm_at_s;
  while (next_ < scenario_.timeline.size() && scenario_.timeline[next_].at_s <= t) {
    const ScenarioEvent& e = scenario_.timeline[next_++];
    if (e.roll_deg) ref_.roll = *e.roll_deg * kRadPerDeg;
    if (e.pitch_deg) ref_.pitch = *e.pitch_deg * kRadPerDeg;
    if (e.yaw_deg) ref_.yaw = wrap(*e.yaw_deg * kRadPerDeg);
    if (e.altitude_m) ref_.altitude_m = *e.altitude_m;
    if (e.speed_mps) ref_.speed_mps = *e.speed_mps;
    if (e.yaw_rate_dps) ref_.yaw_rate = *e.yaw_rate_dps * kRadPerDeg;
    if (e.wind_mps) wind_ = *e.wind_mps;
    if (e.gust) gusts_.emplace_back(e.at_s, *e.gust);
  }
}

MotorMask ScenarioClock::detected(double t, double detection_s) const {
  MotorMask mask = 0;
  for (const MotorFailure& f : failures_) {
    if (reported_outside(f.kind) && due(t, f.at_s + detection_s)) mask |= MotorMask{1} << f.motor;
  }
  return mask;
}

DetectionScorer::DetectionScorer(const std::vector<MotorFailure>& failures) {
  for (const MotorFailure& f : failures) outcomes_.push_back({f, -1.0, -1, DetectionSource::kNone});
}

void DetectionScorer::add(double t, MotorMask declared, DetectionSource source) {
  const MotorMask fresh = declared & ~seen_;
  seen_ |= declared;
  if (declared == 0) seen_ = 0;  // disarmed: a new flight
  for (int m = 0; fresh >> m != 0; ++m) {
    if (((fresh >> m) & 1U) == 0) continue;
    declarations_.push_back({t, m, source});
    // The earliest undetected thrust-losing failure of this motor; else the
    // earliest undetected one of any motor (named wrong).
    FailureOutcome* match = nullptr;
    FailureOutcome* other = nullptr;
    for (FailureOutcome& o : outcomes_) {
      if (o.detected_at_s >= 0 || !loses_thrust(o.failure.kind) || o.failure.at_s > t) continue;
      if (o.failure.motor == m && match == nullptr) match = &o;
      if (other == nullptr) other = &o;
    }
    FailureOutcome* o = match != nullptr ? match : other;
    if (o != nullptr) {
      o->detected_at_s = t;
      o->detected_motor = m;
      o->detected_by = source;
    }
    if (match == nullptr) ++false_detections_;
  }
}

void DetectionScorer::finish(SimResult& r) const {
  r.failures = outcomes_;
  r.false_detections = false_detections_;
  r.declarations = declarations_;
}

bool end_of_period(SimResult& r, const VehicleModel& vehicle, std::int64_t k, double t_end) {
  r.min_battery_v = std::min(r.min_battery_v, vehicle.battery().terminal_v());
  r.cycles = k + 1;
  if (!vehicle.crashed()) return false;
  r.crashed = true;
  r.crash_reason = vehicle.crash_reason();
  r.crash_time_s = t_end;
  return true;
}

Environment ScenarioClock::environment(double t) const {
  Environment env;
  env.wind_ned = wind_;
  for (const auto& [start, g] : gusts_) {
    if (t >= start && t < start + g.for_s) {
      env.force_world += g.force_n;
      env.torque_body += g.torque_nm;
    }
  }
  return env;
}

Scorer::Scorer(const Scenario& scenario, const config::Config& config)
    : from_s_(scenario.score_from_s),
      to_s_(scenario.score_to_s),
      wheeled_(config.thrust_range() == ThrustRange::kBipolar),
      controlled_(config.geometry.controlled),
      period_s_(1.0 / config.loop_rate_hz) {}

void Scorer::add_flight(double t, const VehicleModel& vehicle) {
  const BodyState& b = vehicle.body();
  const Eigen::Vector2d here(b.position.x(), b.position.y());
  if (!drift_from_set_ && failure_s_ >= 0 && t >= failure_s_) {
    drift_from_ = here;
    drift_from_set_ = true;
  }
  const bool landed = vehicle.landed();
  if (touchdown_s_ < 0) drift_to_ = here;
  if (landed && !was_landed_ && vehicle.taken_off() && touchdown_s_ < 0) {
    touchdown_s_ = t;
    touchdown_speed_ = vehicle.touchdown_speed();
  }
  was_landed_ = landed;
  if (!landed && vehicle.taken_off()) {
    max_rate_ = std::max(max_rate_, b.rates.norm());
    max_tilt_ = std::max(max_tilt_, tilt(b.attitude) / kRadPerDeg);
  }
  if (failure_s_ >= 0 && t >= failure_s_ && touchdown_s_ < 0 && !landed) {
    Settle s;
    s.t = t;
    s.rate = b.rates.norm();
    for (int i = 0; i < vehicle.motors(); ++i) s.thrust.push_back(vehicle.thrust_n(i));
    settle_.push_back(std::move(s));
    while (settle_begin_ < settle_.size() && settle_[settle_begin_].t < t - kSettleWindowS) {
      ++settle_begin_;
    }
    if (settle_begin_ > 4096) {  // long runs: keep only the window
      settle_.erase(settle_.begin(), settle_.begin() + static_cast<std::ptrdiff_t>(settle_begin_));
      settle_begin_ = 0;
    }
  }
}

void Scorer::add(double t, const Reference& ref, const ControllerCommand& cmd,
                 const VehicleModel& vehicle, bool armed, std::uint8_t axis_limited) {
  if (armed) ++armed_cycles_;
  if (!wheeled_) add_flight(t, vehicle);
  if (!wheeled_ && ref.altitude_m > 0 &&
      std::abs(ref.altitude_m + vehicle.body().position.z()) < kReachedM) {
    ever_reached_ = true;
  }
  if (t < from_s_ || t > to_s_) return;
  ++scored_;
  const BodyState& b = vehicle.body();
  if (wheeled_) {
    const double ds = ref.speed_mps - vehicle.forward_speed();
    const double dr = (ref.yaw_rate - b.rates.z()) / kRadPerDeg;
    speed_sq_ += ds * ds;
    rate_sq_ += dr * dr;
  } else {
    const Eigen::Vector3d z = b.attitude * Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d z_sp = cmd.attitude_sp * Eigen::Vector3d::UnitZ();
    const double att = std::acos(std::clamp(z.dot(z_sp), -1.0, 1.0)) / kRadPerDeg;
    const double yaw = wrap(ref.yaw - heading(b.attitude)) / kRadPerDeg;
    att_sq_ += att * att;
    yaw_sq_ += yaw * yaw;
    att_max_ = std::max(att_max_, att);
    if (failure_s_ >= 0 && t >= failure_s_ && t <= failure_s_ + kFailureWindowS) {
      failure_att_max_ = std::max(failure_att_max_, att);
    }
    // A drop counts once the vehicle has reached the commanded altitude
    // (within kReachedM) since the command last changed: a climb still on
    // its way is not a loss.
    const double below = ref.altitude_m + b.position.z();
    if (ref.altitude_m != commanded_altitude_) {
      commanded_altitude_ = ref.altitude_m;
      reached_ = false;
    }
    if (below < kReachedM) reached_ = true;
    if (reached_) altitude_loss_ = std::max(altitude_loss_, below);
    altitude_error_max_ = std::max(altitude_error_max_, std::abs(below));
  }
  if (armed && (axis_limited & controlled_) != 0) ++saturated_;
}

void Scorer::finish(SimResult& r) const {
  r.attitude_error_max_deg = att_max_;
  r.failure_attitude_error_max_deg = failure_att_max_;
  r.altitude_loss_m = altitude_loss_;
  r.armed_s = static_cast<double>(armed_cycles_) * period_s_;
  r.reached_altitude = ever_reached_;
  r.altitude_error_max_m = altitude_error_max_;
  r.touchdown_speed_mps = touchdown_speed_;
  r.touchdown_time_s = touchdown_s_;
  r.drift_m = (drift_to_ - drift_from_).norm();
  r.max_spin_rate_rad_s = max_rate_;
  r.max_thrust_axis_tilt_deg = max_tilt_;
  if (settle_begin_ < settle_.size()) {
    const auto n = static_cast<double>(settle_.size() - settle_begin_);
    r.settled_thrust_n.assign(settle_.back().thrust.size(), 0.0);
    for (std::size_t k = settle_begin_; k < settle_.size(); ++k) {
      r.settled_spin_rate_rad_s += settle_[k].rate / n;
      for (std::size_t i = 0; i < r.settled_thrust_n.size(); ++i)
        r.settled_thrust_n[i] += settle_[k].thrust[i] / n;
    }
  }
  if (scored_ == 0) return;
  const auto n = static_cast<double>(scored_);
  r.attitude_error_rms_deg = std::sqrt(att_sq_ / n);
  r.yaw_error_rms_deg = std::sqrt(yaw_sq_ / n);
  r.speed_error_rms_mps = std::sqrt(speed_sq_ / n);
  r.yaw_rate_error_rms_dps = std::sqrt(rate_sq_ / n);
  r.saturated_fraction = static_cast<double>(saturated_) / n;
}

config::Config scenario_config(const config::Config& config_in, const Scenario& scenario) {
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
  return config;
}

SimResult run_lockstep(const config::Config& config_in, Mixer mixer, const Scenario& scenario,
                       const SimOptions& options, const FrameObserver& observer) {
  const auto wall_start = std::chrono::steady_clock::now();
  const bool wheeled = config_in.thrust_range() == ThrustRange::kBipolar;
  const config::Config config = scenario_config(config_in, scenario);
  VehicleModel vehicle(config);
  loop::ControlLoop loop(config, std::move(mixer));
  Controller controller = Controller::for_vehicle(config, loop.mixer(), vehicle);
  ScenarioClock clock(scenario, config, options.failures);
  Sensors sensors(scenario.noise, options.seed);
  EscTelemetryModel esc_telemetry(config.motors(), options.seed);
  AttitudeSensor attitude_sensor(scenario.noise.gyro_rad_s, options.seed);
  DetectionScorer detections(clock.failures());

  const SimulationPeriod periods(
      config.loop_rate_hz, options.duration_s > 0 ? options.duration_s : scenario.duration_s);
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

    const BodyState measured = sensors.measure(vehicle.body());
    const ControllerCommand cmd =
        controller.update(ref, measured, sensors.speed(vehicle.forward_speed()), mixer_armed,
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
      const loop::EscTelemetrySample& esc = esc_telemetry.sample(t, now, vehicle, health);
      if (esc.count > 0) loop.on_esc_telemetry(esc, now, now);
    }
    if (loop.reads_attitude()) loop.on_attitude(attitude_sensor.sample(vehicle.body(), now), now, now);
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
    detections.add(t, cycle);

    periods.integrate(vehicle, cycle.mix.output, cycle.mix.direction, health, clock, t);
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
