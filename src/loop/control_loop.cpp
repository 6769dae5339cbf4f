#include "loop/control_loop.hpp"

#include "loop/durations.hpp"

#include <motormix/config/config_error.hpp>

#include <algorithm>
#include <cmath>
#include <utility>

namespace motormix::loop {

ControlLoop::ControlLoop(const config::Config& config, Mixer mixer)
    : mixer_(std::move(mixer)),
      thrust_range_(config.thrust_range()),
      yaw_source_(config.inputs.yaw_source),
      setpoint_timeout_us_(seconds_to_us(config.inputs.setpoint_timeout_s)),
      pid_timeout_us_(seconds_to_us(config.inputs.pid_timeout_s)),
      failsafe_action_(config.inputs.failsafe),
      hold_last_us_(seconds_to_us(config.inputs.hold_last_s)),
      max_future_us_(seconds_to_us(config.inputs.max_future_s)),
      arming_(config.inputs.arm_max_throttle),
      motor_test_(config.motor_test, mixer_.motors(), setpoint_timeout_us_),
      spool_up_(seconds_to_us(config.spool_up_s)),
      failures_(config.failed_motors, mixer_.motors()) {
  if (config.battery) battery_.emplace(*config.battery);
  if (config.failure_detection) detection_.emplace(config);
  if (config.inputs.units == config::InputUnits::kPhysical) {
    physical_ = PhysicalInputs::build(config, mixer_);
    if (!physical_) {
      throw config::ConfigError(
          "inputs.units: physical, but the vehicle's torque per demand cannot be inverted at "
          "hover (a rotor layout that cannot make each torque): use normalized");
    }
  }
  if (config.motor_loss) landing_.emplace(config);
  // What the status says is being read (constant for the configuration).
  result_.detector_sources =
      config.failure_detection ? config.failure_detection->detector.sources : 0;
  result_.motor_loss_on = config.motor_loss.has_value();
  esc_last_utime_.fill(kNever);
  mixer_.disarm(result_.mix);
  record_vehicle_state(0);
}

bool ControlLoop::reads_esc_telemetry(const config::Config& config) {
  return config.failure_detection && (config.failure_detection->detector.sources &
                                      static_cast<std::uint8_t>(DetectorSources::kTelemetry)) != 0;
}

bool ControlLoop::reads_attitude(const config::Config& config) {
  return (config.failure_detection && (config.failure_detection->detector.sources &
                                       static_cast<std::uint8_t>(DetectorSources::kRates)) != 0) ||
         config.motor_loss.has_value();
}

void ControlLoop::count(Rejection rejection) {
  switch (rejection) {
    case Rejection::kNone:
      break;
    case Rejection::kNonFinite:
      ++counters_.rejected_nonfinite;
      break;
    case Rejection::kOutOfRange:
      ++counters_.rejected_range;
      break;
    case Rejection::kOutOfOrder:
      ++counters_.rejected_out_of_order;
      break;
    case Rejection::kFromFuture:
      break;  // counted where it is detected
    case Rejection::kWrongSize:
      ++counters_.rejected_size;
      break;
  }
}

bool ControlLoop::from_future(std::int64_t utime, std::int64_t wall_us) {
  if (static_cast<double>(utime) - static_cast<double>(wall_us) <=
      static_cast<double>(max_future_us_)) {
    return false;
  }
  ++counters_.rejected_future;
  return true;
}

Rejection ControlLoop::on_setpoint(const SetpointSample& in, std::int64_t now_us,
                                   std::int64_t wall_us) {
  if (from_future(in.utime, wall_us)) return Rejection::kFromFuture;
  SetpointSample sample = in;
  // Newtons and newton-metres to demands; NaN stays NaN for the checks.
  if (physical_ && std::isfinite(in.throttle) && std::isfinite(in.yaw)) {
    sample.throttle = physical_->throttle_for(in.throttle);
    sample.yaw = physical_->torques_for(Eigen::Vector3d(0.0, 0.0, in.yaw)).z();
  }
  const Rejection rejection = check_setpoint(sample, thrust_range_, setpoint_.last_utime());
  count(rejection);
  if (rejection != Rejection::kNone) return rejection;
  ++counters_.setpoint_received;
  setpoint_.accept(sample, now_us);
  arming_.on_setpoint(sample.armed);
  if (sample.armed) motor_test_.on_armed_setpoint(now_us);
  return rejection;
}

MotorTestResult ControlLoop::on_motor_test(const MotorTestSample& s, std::int64_t now_us,
                                           std::int64_t wall_us) {
  const MotorTestResult r =
      motor_test_.request(s, now_us, arming_.state() == LoopState::kDisarmed,
                          [&](std::int64_t utime) { return from_future(utime, wall_us); });
  if (r != MotorTestResult::kOk) {
    ++counters_.motor_tests_refused;
  } else if (s.motor != 0) {
    ++counters_.motor_tests_started;
  }
  result_.motor_test_request_utime = motor_test_.last_request_utime();
  result_.motor_test_result = motor_test_.last_result();
  return r;
}

Rejection ControlLoop::on_pid(const PidSample& in, std::int64_t now_us, std::int64_t wall_us) {
  if (from_future(in.utime, wall_us)) return Rejection::kFromFuture;
  PidSample pid = in;
  if (physical_ && std::isfinite(in.roll) && std::isfinite(in.pitch) && std::isfinite(in.yaw)) {
    const Eigen::Vector3d d = physical_->torques_for(Eigen::Vector3d(in.roll, in.pitch, in.yaw));
    pid.roll = d.x();
    pid.pitch = d.y();
    pid.yaw = d.z();
  }
  const Rejection rejection = check_pid(pid, pid_.last_utime());
  count(rejection);
  if (rejection != Rejection::kNone) return rejection;
  ++counters_.pid_received;
  pid_.accept(pid, now_us);
  return rejection;
}

Rejection ControlLoop::on_motor_status(const MotorStatusSample& sample, std::int64_t now_us,
                                       std::int64_t wall_us) {
  if (from_future(sample.utime, wall_us)) return Rejection::kFromFuture;
  const Rejection rejection =
      check_motor_status(sample, mixer_.motors(), motor_status_.last_utime());
  count(rejection);
  if (rejection != Rejection::kNone) return rejection;
  ++counters_.motor_status_received;
  motor_status_.accept(sample, now_us);
  failures_.set_reported(sample.failed);
  return rejection;
}

Rejection ControlLoop::on_battery(const BatterySample& sample, std::int64_t now_us,
                                  std::int64_t wall_us) {
  if (!battery_) return Rejection::kNone;  // not configured: not read at all
  if (from_future(sample.utime, wall_us)) return Rejection::kFromFuture;
  Rejection rejection = check_battery(sample, battery_reading_.last_utime());
  if (rejection == Rejection::kNone) {
    switch (battery_->add(sample.voltage, now_us)) {
      case BatteryCompensation::Reading::kAccepted:
        break;
      case BatteryCompensation::Reading::kNonFinite:
        rejection = Rejection::kNonFinite;
        break;
      case BatteryCompensation::Reading::kImplausible:
        rejection = Rejection::kOutOfRange;
        break;
    }
  }
  count(rejection);
  if (rejection != Rejection::kNone) return rejection;
  ++counters_.battery_received;
  battery_reading_.accept(sample, now_us);
  return rejection;
}

Rejection ControlLoop::on_esc_telemetry(const EscTelemetrySample& sample, std::int64_t now_us,
                                        std::int64_t wall_us) {
  if (!reads_esc_telemetry()) return Rejection::kNone;
  if (from_future(sample.utime, wall_us)) return Rejection::kFromFuture;
  const EscTelemetryVerdict verdict = check_esc_telemetry(sample, mixer_.motors(), esc_last_utime_);
  if (verdict.message != Rejection::kNone) {
    count(verdict.message);
    return verdict.message;
  }
  // Each refused reading is counted under its reason; the others are read.
  Rejection first_refusal = Rejection::kNone;
  for (int i = 0; i < sample.count; ++i) {
    const Rejection r = verdict.reading[static_cast<std::size_t>(i)];
    count(r);
    if (first_refusal == Rejection::kNone) first_refusal = r;
  }
  if (verdict.taken == 0) return first_refusal;
  ++counters_.esc_telemetry_received;
  esc_received_us_ = now_us;
  for (int i = 0; i < sample.count; ++i) {
    if (((verdict.taken >> i) & 1U) == 0) continue;
    const int motor = sample.readings[static_cast<std::size_t>(i)].motor;
    esc_last_utime_[static_cast<std::size_t>(motor - 1)] = sample.utime;
  }
  detection_->on_telemetry(sample, verdict.taken, now_us);
  return Rejection::kNone;
}

Rejection ControlLoop::on_attitude(const AttitudeSample& sample, std::int64_t now_us,
                                   std::int64_t wall_us) {
  if (!reads_attitude()) return Rejection::kNone;
  if (from_future(sample.utime, wall_us)) return Rejection::kFromFuture;
  const Rejection rejection = check_attitude(sample, attitude_.last_utime());
  count(rejection);
  if (rejection != Rejection::kNone) return rejection;
  ++counters_.attitude_received;
  attitude_.accept(sample, now_us);
  if (detection_ && detection_->uses_rates()) detection_->on_attitude(sample, now_us);
  return rejection;
}

void ControlLoop::detect(std::int64_t now_us, bool setpoint_fresh, double ramp) {
  result_.detection_changed = false;
  if (!detection_) return;
  const LoopState state = arming_.state();
  if (state == LoopState::kDisarmed) {
    // Declarations stand until disarming; a new flight is judged afresh.
    if (failures_.detected() != 0 || detection_->detection().source != DetectionSource::kNone) {
      detection_->reset();
      failures_.set_detected(0);
      result_.detection_changed = true;
    }
  }
  const bool allowed = state == LoopState::kArmed && ramp >= 1.0 && !motor_test_.running() &&
                       setpoint_fresh && setpoint_.sample().throttle >= detection_->min_throttle();
  const MotorMask before = failures_.detected();
  const Detection& d =
      detection_->update(result_.mix.output, failures_.in_force(), allowed, now_us);
  failures_.set_detected(d.failed);
  if (failures_.detected() != before) result_.detection_changed = true;
  result_.detection = d;
}

void ControlLoop::land(std::int64_t now_us, double ramp) {
  result_.landing_changed = false;
  if (!landing_) return;
  const LandingReport before = landing_->report();
  const LoopState state = arming_.state();
  if (state == LoopState::kDisarmed) {
    landing_->disarmed();
  } else {
    if (previous_state_ == LoopState::kDisarmed) landing_->armed();
    LandingRunner::Inputs in;
    in.flying = ramp >= 1.0 && !motor_test_.running();
    in.may_start = state == LoopState::kArmed;
    in.failed = result_.failed;
    in.attitude = &attitude_;
    in.throttle = setpoint_.sample().throttle;
    if (landing_->cycle(in, now_us, mixer_.output_stage(), result_.mix) &&
        landing_->report().state == DescentPhase::kLanded) {
      arming_.disarm();
      mixer_.disarm(result_.mix);
    }
  }
  const LandingReport& after = landing_->report();
  result_.landing = after;
  result_.landing_changed =
      after.state != before.state || after.motor != before.motor || after.failed != before.failed;
}

void ControlLoop::record_vehicle_state(std::int64_t now_us) {
  result_.failed = failures_.in_force();
  const Mixer::FailureReport& report = failures_.report(mixer_);
  result_.failure = report.handling;
  result_.held = report.held;
  result_.authority = report.authority;
  result_.battery = battery_ ? battery_->state(now_us) : BatteryState::kOff;
  result_.battery_v =
      battery_ && std::isfinite(battery_->filtered_v()) ? battery_->filtered_v() : 0.0;
  result_.thrust_gain = battery_ ? battery_->gain(now_us) : 1.0;
  result_.input_age_ms = {setpoint_.age_ms(now_us), pid_.age_ms(now_us),
                          battery_reading_.age_ms(now_us), motor_status_.age_ms(now_us)};
}

void ControlLoop::enter_failsafe(FailsafeReason reason, std::int64_t now_us) {
  arming_.enter_failsafe(reason, now_us);
  ++counters_.failsafe_events;
}

void ControlLoop::mix_inputs(const AxisVector& demand, std::int64_t now_us, double ramp) {
  const double dt_s =
      last_cycle_us_ == kNever ? 0.0 : static_cast<double>(now_us - last_cycle_us_) / 1e6;
  AxisVector compensated = demand * ramp;
  compensated[index(Axis::kThrust)] *= result_.thrust_gain;
  if (mixer_.mix(compensated, result_.mix, dt_s, result_.failed) == MixStatus::kNonFiniteDemand) {
    // Unreachable while message checks hold; kept so the promise does not
    // depend on them.
    if (arming_.state() == LoopState::kArmed) {
      enter_failsafe(FailsafeReason::kInvalidInput, now_us);
    }
    mixer_.disarm(result_.mix);
  } else if (ramp < 1.0) {
    SpoolUp::blend(mixer_.output_stage(), ramp, result_.mix);
  }
}

const CycleResult& ControlLoop::cycle(std::int64_t now_us) {
  ++counters_.cycles;
  const LoopState previous = result_.state;
  const bool setpoint_fresh = setpoint_.fresh(now_us, setpoint_timeout_us_);
  const bool pid_fresh = pid_.fresh(now_us, pid_timeout_us_);
  result_.setpoint_stale = !setpoint_fresh;
  result_.pid_stale = !pid_fresh;
  result_.setpoint_utime = setpoint_.utime_or_zero();
  result_.pid_utime = pid_.utime_or_zero();

  const SetpointSample& setpoint = setpoint_.sample();
  const PidSample& pid = pid_.sample();
  Arming::Inputs in;
  in.stalled = last_cycle_us_ != kNever &&
               now_us - last_cycle_us_ > std::min(setpoint_timeout_us_, pid_timeout_us_);
  in.setpoint_fresh = setpoint_fresh;
  in.pid_fresh = pid_fresh;
  in.setpoint_armed = setpoint.armed;
  in.throttle = setpoint.throttle;
  const Arming::Events events = arming_.update(in, now_us);
  if (events.failsafe_entered) ++counters_.failsafe_events;
  if (events.arming_refused) {
    ++counters_.arming_refused;
    ++(events.refusal == Arming::Refusal::kThrottleHigh
           ? counters_.arming_refused_throttle
           : counters_.arming_refused_not_disarmed_first);
    result_.last_arming_refusal = events.refusal;
  }
  result_.arming_refused = events.refusal;
  if (arming_.state() == LoopState::kArmed) result_.last_arming_refusal = Arming::Refusal::kNone;

  // The spool-up ramp runs from arming; a failsafe that keeps mixing (hold
  // the last inputs, idle) keeps it, so no output jumps up on the way down.
  const double ramp = spool_up_.ramp(now_us - arming_.armed_since_us());
  detect(now_us, setpoint_fresh, ramp);
  record_vehicle_state(now_us);
  result_.attitude_age_ms = attitude_.age_ms(now_us);
  result_.esc_telemetry_age_ms =
      esc_received_us_ < 0 ? -1.0 : static_cast<double>(now_us - esc_received_us_) / 1e3;
  const double yaw = yaw_source_ == config::YawSource::kPid ? pid.yaw : setpoint.yaw;
  const AxisVector demand(pid.roll, pid.pitch, yaw, setpoint.throttle);
  const LoopState state = arming_.state();
  result_.spooling_up = state == LoopState::kArmed && ramp < 1.0;
  result_.spool_up = state == LoopState::kArmed ? ramp : 0.0;
  if (state == LoopState::kArmed) {
    mix_inputs(demand, now_us, ramp);
  } else if (state == LoopState::kFailsafe &&
             failsafe_action_ == config::FailsafeAction::kHoldLast &&
             now_us - arming_.failsafe_since_us() <= hold_last_us_) {
    mix_inputs(demand, now_us, ramp);
  } else if (state == LoopState::kFailsafe && failsafe_action_ == config::FailsafeAction::kIdle) {
    mix_inputs(AxisVector::Zero(), now_us, ramp);
  } else {
    mixer_.disarm(result_.mix);
  }
  land(now_us, ramp);
  previous_state_ = arming_.state();
  // A motor test runs only while disarmed, until its end time.
  motor_test_.expire(now_us, arming_.state() == LoopState::kDisarmed);
  if (motor_test_.running()) motor_test_.spin(mixer_, result_.mix);
  result_.motor_test = motor_test_.motor();
  result_.motor_test_throttle = motor_test_.throttle();
  result_.motor_test_changed = motor_test_.take_changed();
  result_.state = arming_.state();
  result_.reason = arming_.reason();
  result_.state_changed = result_.state != previous;
  last_cycle_us_ = now_us;
  return result_;
}

}  // namespace motormix::loop
