#include "loop/control_loop.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <utility>

namespace motormix::loop {

namespace {

std::int64_t seconds_to_us(double s) { return static_cast<std::int64_t>(std::llround(s * 1e6)); }

bool fresh(std::int64_t received_us, std::int64_t now_us, std::int64_t timeout_us) {
  // received_us is kNever (most negative) until the first message: compare
  // without subtracting to stay clear of overflow.
  return received_us != std::numeric_limits<std::int64_t>::min() &&
         now_us - received_us <= timeout_us;
}

}  // namespace

const char* to_string(LoopState state) {
  switch (state) {
    case LoopState::kDisarmed:
      return "disarmed";
    case LoopState::kArmed:
      return "armed";
    case LoopState::kFailsafe:
      return "failsafe";
  }
  return "?";
}

const char* to_string(FailsafeReason reason) {
  switch (reason) {
    case FailsafeReason::kNone:
      return "none";
    case FailsafeReason::kSetpointStale:
      return "setpoint stale";
    case FailsafeReason::kPidStale:
      return "pid stale";
    case FailsafeReason::kLoopStalled:
      return "loop stalled";
    case FailsafeReason::kInvalidInput:
      return "invalid input";
  }
  return "?";
}

const char* to_string(MotorTestResult result) {
  switch (result) {
    case MotorTestResult::kOk:
      return "ok";
    case MotorTestResult::kRefusedDisabled:
      return "motor tests are disabled (motor_test.enabled: false)";
    case MotorTestResult::kRefusedNotDisarmed:
      return "the mixer is armed or in failsafe";
    case MotorTestResult::kRefusedArmedSetpoint:
      return "an armed setpoint arrived within the input timeout";
    case MotorTestResult::kRefusedThrottle:
      return "throttle outside 0..motor_test.max_throttle";
    case MotorTestResult::kRefusedDuration:
      return "duration outside 0..motor_test.max_seconds";
    case MotorTestResult::kRefusedMotor:
      return "no such motor";
    case MotorTestResult::kRefusedInvalid:
      return "not finite, out of order or from the future";
  }
  return "?";
}

ControlLoop::ControlLoop(const config::Config& config, Mixer mixer)
    : mixer_(std::move(mixer)),
      thrust_range_(config.thrust_range()),
      yaw_source_(config.inputs.yaw_source),
      setpoint_timeout_us_(seconds_to_us(config.inputs.setpoint_timeout_s)),
      pid_timeout_us_(seconds_to_us(config.inputs.pid_timeout_s)),
      failsafe_action_(config.inputs.failsafe),
      hold_last_us_(seconds_to_us(config.inputs.hold_last_s)),
      max_future_us_(seconds_to_us(config.inputs.max_future_s)),
      arm_max_throttle_(config.inputs.arm_max_throttle),
      config_failed_(config.failed_motors),
      spool_up_us_(seconds_to_us(config.spool_up_s)),
      motor_test_settings_(config.motor_test) {
  if (config.battery) battery_.emplace(*config.battery);
  mixer_.disarm(result_.mix);
  record_vehicle_state(0);
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

Rejection ControlLoop::on_setpoint(const SetpointSample& sample, std::int64_t now_us,
                                   std::int64_t wall_us) {
  if (from_future(sample.utime, wall_us)) return Rejection::kFromFuture;
  const Rejection rejection = check_setpoint(sample, thrust_range_, last_setpoint_utime_);
  count(rejection);
  if (rejection != Rejection::kNone) return rejection;
  ++counters_.setpoint_received;
  setpoint_ = sample;
  last_setpoint_utime_ = sample.utime;
  setpoint_received_us_ = now_us;
  if (!sample.armed) arm_permitted_ = true;
  if (sample.armed) {
    last_armed_setpoint_us_ = now_us;
    end_motor_test();  // the pilot wants to fly: no motor spins on its own any more
  }
  return rejection;
}

void ControlLoop::end_motor_test() {
  if (test_motor_ < 0) return;
  test_motor_ = -1;
  test_changed_ = true;
}

MotorTestResult ControlLoop::on_motor_test(const MotorTestSample& s, std::int64_t now_us,
                                           std::int64_t wall_us) {
  MotorTestResult r = MotorTestResult::kOk;
  if (!motor_test_settings_.enabled) {
    r = MotorTestResult::kRefusedDisabled;
  } else if (!std::isfinite(s.throttle) || !std::isfinite(s.duration_s) ||
             from_future(s.utime, wall_us) ||
             (last_motor_test_utime_ != kNever && s.utime <= last_motor_test_utime_ &&
              last_motor_test_utime_ - s.utime < kPublisherRestartUs)) {
    // Out of order, unless far enough back to be a client with a new clock.
    r = MotorTestResult::kRefusedInvalid;
  } else if (s.motor == 0) {
    end_motor_test();  // a request to stop is always obeyed
  } else if (result_.state != LoopState::kDisarmed) {
    r = MotorTestResult::kRefusedNotDisarmed;
  } else if (last_armed_setpoint_us_ != kNever &&
             now_us - last_armed_setpoint_us_ <= setpoint_timeout_us_) {
    r = MotorTestResult::kRefusedArmedSetpoint;
  } else if (s.motor < 0 || s.motor > mixer_.motors()) {
    r = MotorTestResult::kRefusedMotor;
  } else if (s.throttle < 0.0 || s.throttle > motor_test_settings_.max_throttle) {
    r = MotorTestResult::kRefusedThrottle;
  } else if (s.duration_s <= 0.0 || s.duration_s > motor_test_settings_.max_seconds) {
    r = MotorTestResult::kRefusedDuration;
  } else {
    test_motor_ = s.motor - 1;
    test_throttle_ = s.throttle;
    test_end_us_ = now_us + seconds_to_us(s.duration_s);
    test_changed_ = true;
    ++counters_.motor_tests_started;
  }
  if (r != MotorTestResult::kOk) ++counters_.motor_tests_refused;
  if (r != MotorTestResult::kRefusedInvalid) last_motor_test_utime_ = s.utime;
  result_.motor_test_request_utime = s.utime;
  result_.motor_test_result = r;
  return r;
}

// The test motor alone through the output stage (its idle, linearization,
// limits and direction pin), every other output at its disarmed value.
void ControlLoop::spin_test_motor() {
  mixer_.disarm(result_.mix);
  const int n = mixer_.motors();
  MotorVector command = MotorVector::Zero(n);
  command[test_motor_] = test_throttle_;
  const MotorMask all = (MotorMask{1} << n) - 1;
  const MotorMask others = all & ~(MotorMask{1} << test_motor_);
  mixer_.output_stage().armed(command, result_.mix.output, result_.mix.direction, 0.0, false,
                              others);
  result_.mix.command = command;
  result_.mix.armed = false;
}

Rejection ControlLoop::on_pid(const PidSample& pid, std::int64_t now_us, std::int64_t wall_us) {
  if (from_future(pid.utime, wall_us)) return Rejection::kFromFuture;
  const Rejection rejection = check_pid(pid, last_pid_utime_);
  count(rejection);
  if (rejection != Rejection::kNone) return rejection;
  ++counters_.pid_received;
  pid_ = pid;
  last_pid_utime_ = pid.utime;
  pid_received_us_ = now_us;
  return rejection;
}

Rejection ControlLoop::on_motor_status(const MotorStatusSample& sample, std::int64_t now_us,
                                       std::int64_t wall_us) {
  if (from_future(sample.utime, wall_us)) return Rejection::kFromFuture;
  const Rejection rejection = check_motor_status(sample, mixer_.motors(), last_motor_status_utime_);
  count(rejection);
  if (rejection != Rejection::kNone) return rejection;
  ++counters_.motor_status_received;
  reported_failed_ = sample.failed;
  last_motor_status_utime_ = sample.utime;
  motor_status_received_us_ = now_us;
  return rejection;
}

Rejection ControlLoop::on_battery(const BatterySample& sample, std::int64_t now_us,
                                  std::int64_t wall_us) {
  if (!battery_) return Rejection::kNone;  // not configured: not read at all
  if (from_future(sample.utime, wall_us)) return Rejection::kFromFuture;
  Rejection rejection = check_battery(sample, last_battery_utime_);
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
  last_battery_utime_ = sample.utime;
  battery_received_us_ = now_us;
  return rejection;
}

void ControlLoop::record_vehicle_state(std::int64_t now_us) {
  const MotorMask all = (MotorMask{1} << mixer_.motors()) - 1;
  result_.failed = (config_failed_ | reported_failed_) & all;
  if (!failure_report_known_ || failure_report_for_ != result_.failed) {
    const Mixer::FailureReport report = mixer_.failure_report(result_.failed);
    result_.failure = report.handling;
    result_.held = report.held;
    result_.authority = report.authority;
    failure_report_for_ = result_.failed;
    failure_report_known_ = true;
  }
  result_.battery = battery_ ? battery_->state(now_us) : BatteryState::kOff;
  result_.battery_v =
      battery_ && std::isfinite(battery_->filtered_v()) ? battery_->filtered_v() : 0.0;
  result_.thrust_gain = battery_ ? battery_->gain(now_us) : 1.0;
  const auto age = [&](std::int64_t received) {
    return received == kNever ? -1.0 : static_cast<double>(now_us - received) / 1e3;
  };
  result_.input_age_ms = {age(setpoint_received_us_), age(pid_received_us_),
                          age(battery_received_us_), age(motor_status_received_us_)};
}

void ControlLoop::enter_failsafe(FailsafeReason reason, std::int64_t now_us) {
  result_.state = LoopState::kFailsafe;
  result_.reason = reason;
  arm_permitted_ = false;
  failsafe_since_us_ = now_us;
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
    if (result_.state == LoopState::kArmed) enter_failsafe(FailsafeReason::kInvalidInput, now_us);
    mixer_.disarm(result_.mix);
  } else {
    result_.last_armed_allocation = result_.mix.allocation;
    if (ramp < 1.0) {
      // From each disarmed value, taken into the output range (an ESC's
      // zero, output.min, when disarmed sits below it: armed outputs never
      // leave [min, max]), toward the mixed output. Failed motors keep their
      // stop value.
      const OutputStage& stage = mixer_.output_stage();
      for (int i = 0; i < stage.outputs(); ++i) {
        if ((result_.mix.failed >> i) & 1U) continue;
        const OutputChannel& ch = stage.channel(i);
        const double off =
            std::clamp(ch.disarmed, std::min(ch.min, ch.max), std::max(ch.min, ch.max));
        result_.mix.output[i] = off + ramp * (result_.mix.output[i] - off);
      }
    }
  }
}

const CycleResult& ControlLoop::cycle(std::int64_t now_us) {
  ++counters_.cycles;
  const LoopState previous = result_.state;
  const bool setpoint_fresh = fresh(setpoint_received_us_, now_us, setpoint_timeout_us_);
  const bool pid_fresh = fresh(pid_received_us_, now_us, pid_timeout_us_);
  result_.setpoint_stale = !setpoint_fresh;
  result_.pid_stale = !pid_fresh;
  result_.setpoint_utime = setpoint_received_us_ == kNever ? 0 : setpoint_.utime;
  result_.pid_utime = pid_received_us_ == kNever ? 0 : pid_.utime;

  const bool stalled = last_cycle_us_ != kNever &&
                       now_us - last_cycle_us_ > std::min(setpoint_timeout_us_, pid_timeout_us_);
  switch (result_.state) {
    case LoopState::kArmed:
      if (stalled) {
        enter_failsafe(FailsafeReason::kLoopStalled, now_us);
      } else if (!setpoint_fresh) {
        enter_failsafe(FailsafeReason::kSetpointStale, now_us);
      } else if (!pid_fresh) {
        enter_failsafe(FailsafeReason::kPidStale, now_us);
      } else if (!setpoint_.armed) {
        result_.state = LoopState::kDisarmed;
      }
      break;
    case LoopState::kFailsafe:
      if (setpoint_fresh && !setpoint_.armed) {
        result_.state = LoopState::kDisarmed;
        result_.reason = FailsafeReason::kNone;
      }
      break;
    case LoopState::kDisarmed:
      if (setpoint_fresh && pid_fresh && setpoint_.armed && arm_permitted_) {
        if (std::abs(setpoint_.throttle) <= arm_max_throttle_) {
          result_.state = LoopState::kArmed;
          armed_since_us_ = now_us;
        } else if (!arm_refused_logged_) {
          ++counters_.arming_refused;
          arm_refused_logged_ = true;  // once per request, not once per cycle
        }
      }
      if (!setpoint_.armed) arm_refused_logged_ = false;
      break;
  }

  record_vehicle_state(now_us);
  const double yaw = yaw_source_ == config::YawSource::kPid ? pid_.yaw : setpoint_.yaw;
  const AxisVector demand(pid_.roll, pid_.pitch, yaw, setpoint_.throttle);
  // The spool-up ramp runs from arming; a failsafe that keeps mixing (hold
  // the last inputs, idle) keeps it, so no output jumps up on the way down.
  const std::int64_t armed_for = now_us - armed_since_us_;
  const double ramp = armed_for >= spool_up_us_
                          ? 1.0
                          : static_cast<double>(armed_for) / static_cast<double>(spool_up_us_);
  result_.spooling_up = result_.state == LoopState::kArmed && ramp < 1.0;
  result_.spool_up = result_.state == LoopState::kArmed ? ramp : 0.0;
  if (result_.state == LoopState::kArmed) {
    mix_inputs(demand, now_us, ramp);
  } else if (result_.state == LoopState::kFailsafe &&
             failsafe_action_ == config::FailsafeAction::kHoldLast &&
             now_us - failsafe_since_us_ <= hold_last_us_) {
    mix_inputs(demand, now_us, ramp);
  } else if (result_.state == LoopState::kFailsafe &&
             failsafe_action_ == config::FailsafeAction::kIdle) {
    mix_inputs(AxisVector::Zero(), now_us, ramp);
  } else {
    mixer_.disarm(result_.mix);
  }
  // A motor test runs only while disarmed, until its end time.
  if (test_motor_ >= 0 && (result_.state != LoopState::kDisarmed || now_us >= test_end_us_)) {
    end_motor_test();
  }
  if (test_motor_ >= 0) spin_test_motor();
  result_.motor_test = test_motor_;
  result_.motor_test_throttle = test_motor_ >= 0 ? test_throttle_ : 0.0;
  result_.motor_test_changed = test_changed_;
  test_changed_ = false;
  result_.state_changed = result_.state != previous;
  last_cycle_us_ = now_us;
  return result_;
}

}  // namespace motormix::loop
