#include "sim/bus/live_sim.hpp"

#include "bus/clock.hpp"
#include "bus/policy_or_error.hpp"
#include "bus/process.hpp"
#include "bus/receive.hpp"
#include "bus/sealed_publisher.hpp"
#include "messages/messages.hpp"
#include "sim/bus/sim_log.hpp"
#include "sim/period.hpp"
#include "sim/plant.hpp"

#include <motormix/battery_t.hpp>
#include <motormix/config/build_mixer.hpp>
#include <motormix/config/security.hpp>
#include <motormix/lockstep_t.hpp>
#include <motormix/mixer_status_t.hpp>
#include <motormix/motor_pwm_t.hpp>
#include <motormix/motor_status_t.hpp>
#include <motormix/pid_t.hpp>
#include <motormix/setpoint_t.hpp>
#include <motormix/signing_policy.hpp>

#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <cmath>
#include <optional>
#include <ostream>
#include <vector>

namespace motormix::sim {

namespace {

using Clock = bus::MonotonicClock;
using bus::wall_us;

// Lockstep: how long the simulator waits for the mixer's answer to a tick.
constexpr double kLockstepWaitS = 5.0;
// The first tick again this often (s) until the mixer answers one.
constexpr double kFirstTickRepeatS = 0.25;

// What the simulated ESCs last heard from the mixer. Decoding happens here,
// inside the callback, and never throws out of it.
struct MixerOutputs {
  signing::Policy* policy = nullptr;  // security: what the sim takes from the mixer
  int motors = 0;
  // In lockstep every time is the simulated one (the tick's), the mixer's
  // stamps too.
  const std::int64_t* lockstep_now = nullptr;
  std::int64_t now() const { return lockstep_now != nullptr ? *lockstep_now : wall_us(); }
  std::int64_t utime = 0;  // the last accepted motor_pwm_t's
  MotorVector outputs;
  DirectionVector direction{};
  bool armed = false;
  Clock::time_point received{};
  bool any = false;
  std::int64_t accepted = 0;
  std::int64_t rejected = 0;
  std::uint8_t axis_limited = 0;
  AxisVector unallocated = AxisVector::Zero();
  std::int64_t statuses = 0;
  // What motormix's own detector has declared, from its status.
  MotorMask detected = 0;
  DetectionSource detected_by = DetectionSource::kNone;
  std::int64_t detected_utime = 0;  // motormix's wall clock, microseconds

  // Both callbacks take messages through the bus's guard (bus::receive):
  // nothing thrown out of them, every refusal counted by reason.
  bus::Refusals refused;
  motor_pwm_t pwm_msg{};
  mixer_status_t status_msg{};

  void on_pwm(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    const motor_pwm_t& msg = pwm_msg;
    if (bus::receive(*policy, rbuf, channel, now(), pwm_msg, refused) != bus::Refusal::kNone ||
        msg.num_motors != motors) {
      ++rejected;
      return;
    }
    for (int i = 0; i < motors; ++i) {
      if (!std::isfinite(msg.pwm[static_cast<std::size_t>(i)])) {
        ++rejected;
        return;
      }
    }
    outputs.resize(motors);
    for (int i = 0; i < motors; ++i) {
      outputs[i] = msg.pwm[static_cast<std::size_t>(i)];
      direction[static_cast<std::size_t>(i)] = msg.direction[static_cast<std::size_t>(i)];
    }
    armed = msg.armed;
    utime = msg.utime;
    received = Clock::now();
    any = true;
    ++accepted;
  }
  void on_status(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    const mixer_status_t& msg = status_msg;
    if (bus::receive(*policy, rbuf, channel, now(), status_msg, refused) != bus::Refusal::kNone)
      return;
    axis_limited = 0;
    for (int a = 0; a < kNumAxes; ++a) {
      if (msg.axis_limited[a]) axis_limited |= static_cast<std::uint8_t>(1U << a);
      unallocated[a] = std::isfinite(msg.unallocated[a]) ? msg.unallocated[a] : 0.0;
    }
    detected = static_cast<MotorMask>(msg.detected_motors);
    detected_by = static_cast<DetectionSource>(msg.detected_by);
    detected_utime = msg.detected_utime;
    ++statuses;
  }
};

}  // namespace

bool run_live(const config::Config& config_in, const Scenario& scenario, const LiveOptions& options,
              LiveResult& result, std::ostream& err) {
  const config::Config config = scenario_config(config_in, scenario, options.sim.realism);
  // A link of its own: it publishes motor_status_t as the mixer does.
  std::optional<signing::Policy> maybe_policy =
      bus::policy_or_error(config, "sim", err, config::kSimulatorLinkOffset);
  if (!maybe_policy) return false;
  signing::Policy& policy = *maybe_policy;
  // SIGTERM / Ctrl-C end the flight early; its result is still written.
  bus::Process process("motormix sim", options.lcm_url, err);
  if (!process.good()) {
    if (process.signals().good()) result.bus_ok = false;  // the bus it is, not the signals
    return false;
  }
  lcm::LCM& lcm = process.lcm();
  bus::ShutdownSignals& signals = process.signals();
  const bool wheeled = config.thrust_range() == ThrustRange::kBipolar;
  Plant plant(config, scenario, options.sim.realism, options.sim.seed);
  const VehicleModel& vehicle = plant.vehicle();
  const Mixer mixer = config::build_mixer(config);  // only linearized by the controller
  Controller controller = Controller::for_vehicle(config, mixer, vehicle);
  ScenarioClock clock(scenario, config, options.sim.failures);
  esc_telemetry_t esc_msg;
  attitude_t attitude_msg;
  Scorer scorer(scenario, config);
  if (!clock.failures().empty()) scorer.failure_at(clock.failures().front().at_s);
  DetectionScorer detections(clock.failures());

  bus::SealedPublisher publisher(lcm, policy);
  const auto publish = [&publisher](const std::string& channel, const auto& msg) {
    publisher.publish(channel, msg);
  };
  MixerOutputs mix;
  mix.policy = &policy;
  mix.motors = config.motors();
  std::int64_t tick_us = 0;    // lockstep: the simulated time of this cycle
  bool answered_once = false;  // lockstep: the mixer has answered a tick
  if (options.lockstep) mix.lockstep_now = &tick_us;
  lcm.subscribe(config.channels.motor_pwm, &MixerOutputs::on_pwm, &mix);
  lcm.subscribe(config.channels.status, &MixerOutputs::on_status, &mix);

  const SimulationPeriod periods(
      config.loop_rate_hz,
      options.sim.duration_s > 0 ? options.sim.duration_s : scenario.duration_s,
      options.sim.realism.imu ? config.vehicle_model.imu.rate_hz : 0.0);
  const double period = periods.period_s;
  MessageSchedule schedule;
  const auto stale_after = std::chrono::duration<double>(
      std::min(config.inputs.setpoint_timeout_s, config.inputs.pid_timeout_s));
  // Without fresh outputs the ESCs stop every motor.
  MotorHealth all_stopped = MotorHealth::healthy(config.motors());
  all_stopped.drive.setZero();

  SimResult& r = result.sim;
  r.min_battery_v = vehicle.battery().terminal_v();
  const auto start = Clock::now();
  vehicle_state_t state;
  for (std::int64_t k = 0; k < periods.cycles; ++k) {
    if (signals.requested()) {
      err << "motormix sim: signal " << signals.last_signal() << ", stopping the flight at "
          << periods.start_of(k) << " s\n";
      result.interrupted = true;
      break;
    }
    const auto due = start + std::chrono::duration_cast<Clock::duration>(
                                 std::chrono::duration<double>(static_cast<double>(k) * period));
    // Serve the bus until this cycle is due (in lockstep: at once); a
    // shutdown signal wakes the wait; the flight ends at the next cycle.
    for (; !options.lockstep;) {
      const auto left = due - Clock::now();
      if (left <= Clock::duration::zero()) break;
      const bus::Woke woke =
          process.wait_ns(std::chrono::duration_cast<std::chrono::nanoseconds>(left).count());
      if (woke.error != 0 || woke.signal) break;
      if (woke.bus) bus::drain(lcm);
    }
    bus::drain(lcm);
    const double t = periods.start_of(k);
    tick_us = kEpochUs + std::llround(t * 1e6);
    const std::int64_t now = options.lockstep ? tick_us : wall_us();
    clock.advance(t);
    const Reference& ref = clock.reference();
    ControllerCommand cmd;
    cmd.attitude_sp = from_euler(ref.roll, ref.pitch, ref.yaw);
    if (options.controller) {
      cmd = controller.update(ref, plant.measured(), plant.measured_speed(), mix.any && mix.armed,
                              vehicle.landed() && !wheeled,
                              mix.armed ? mix.unallocated : AxisVector::Zero(), period);
      setpoint_t sp;
      sp.utime = now;
      sp.throttle = static_cast<float>(cmd.thrust);
      sp.yaw = static_cast<float>(cmd.yaw);
      sp.armed = cmd.armed;
      publish(config.channels.setpoint, sp);
      pid_t pid;
      pid.utime = now;
      pid.roll = static_cast<float>(cmd.roll);
      pid.pitch = static_cast<float>(cmd.pitch);
      pid.yaw = static_cast<float>(cmd.yaw);
      publish(config.channels.pid, pid);
    }
    if (schedule.battery_due(t)) {
      battery_t b;
      b.utime = now;
      b.voltage = static_cast<float>(vehicle.battery().terminal_v());
      publish(config.channels.battery, b);
    }
    if (!wheeled) {
      const loop::EscTelemetrySample& esc = plant.esc_telemetry(t, now, clock.health(t));
      if (esc.count > 0) {
        messages::fill_esc_telemetry_message(esc_msg, esc);
        publish(config.channels.esc_telemetry, esc_msg);
      }
      messages::fill_attitude_message(attitude_msg, plant.attitude(now));
      publish(config.channels.attitude, attitude_msg);
    }
    const MotorMask detected =
        options.sim.undetected ? 0 : clock.detected(t, scenario.failure_detection_s);
    if (schedule.motor_status_due(t, detected)) {
      motor_status_t m;
      m.utime = now;
      m.num_motors = config.motors();
      for (int i = 0; i < m.num_motors; ++i) m.failed.push_back((detected >> i) & 1U);
      publish(config.channels.motor_status, m);
    }
    fill_vehicle_state(state, vehicle, now);
    publish(kVehicleStateChannel, state);

    if (options.lockstep) {
      // The tick after everything of this cycle, then its outputs: the
      // mixer's motor_pwm_t stamped with it (bounded: a mixer gone is an
      // error, never a hang).
      lockstep_t tick;
      tick.utime = tick_us;
      publish(config.channels.lockstep, tick);
      const auto asked = Clock::now();
      auto sent = asked;
      while (!(mix.any && mix.utime == tick_us) &&
             Clock::now() - asked < std::chrono::duration<double>(kLockstepWaitS)) {
        // Until the mixer has answered once, the tick again now and then: a
        // mixer still starting had not subscribed when it went (it refuses
        // a tick it already took, so a repeat costs nothing).
        if (!answered_once &&
            Clock::now() - sent >= std::chrono::duration<double>(kFirstTickRepeatS)) {
          publish(config.channels.lockstep, tick);
          sent = Clock::now();
        }
        const bus::Woke woke = process.wait(answered_once ? 100 : 20);
        if (woke.error != 0 || woke.signal) break;
        if (woke.bus) bus::drain(lcm);
      }
      // A shutdown signal ended the wait: the flight ends at the next cycle.
      if (signals.requested()) continue;
      answered_once = answered_once || (mix.any && mix.utime == tick_us);
      if (!(mix.any && mix.utime == tick_us)) {
        err << "motormix sim: no motor_pwm_t for the tick at " << t << " s within "
            << kLockstepWaitS << " s: is `motormix run --lockstep` running on this bus?\n";
        result.lockstep_lost = true;
        break;
      }
    }
    const bool fresh = options.lockstep ? mix.utime == tick_us
                                        : mix.any && Clock::now() - mix.received <= stale_after;
    const bool armed = fresh && mix.armed;
    scorer.add(t, ref, cmd, vehicle, armed, mix.axis_limited);
    // A declaration at the mixer's stamp, in simulated time (both clocks
    // run in real time here).
    const double declared_t =
        mix.detected_utime > 0 ? t + static_cast<double>(mix.detected_utime - now) / 1e6 : t;
    detections.add(std::min(t, declared_t), mix.detected, mix.detected_by, vehicle);
    plant.integrate(
        periods,
        mix.outputs.size() == config.motors() ? mix.outputs : MotorVector::Zero(config.motors()),
        mix.direction, fresh ? clock.health(t) : all_stopped, clock, t);
    if (end_of_period(r, vehicle, k, t + period)) {
      fill_vehicle_state(state, vehicle, wall_us());  // the crash, for whoever listens
      publish(kVehicleStateChannel, state);
      break;
    }
  }
  scorer.finish(r);
  detections.finish(r);
  r.final_charge = vehicle.battery().charge();
  r.sim_seconds = static_cast<double>(r.cycles) * period;
  r.wall_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  result.pwm_received = mix.accepted;
  result.pwm_rejected = mix.rejected;
  result.refused = mix.refused;
  result.statuses_received = mix.statuses;
  return true;
}

}  // namespace motormix::sim
