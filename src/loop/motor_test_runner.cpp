#include "loop/motor_test_runner.hpp"

#include "loop/durations.hpp"

namespace motormix::loop {

bool MotorTestRunner::out_of_order(std::int64_t utime) const {
  // Not newer than the last valid request, unless far enough back to be a
  // client with a new clock.
  return last_utime_ != kNever && utime <= last_utime_ && last_utime_ - utime < kPublisherRestartUs;
}

MotorTestResult MotorTestRunner::decide(const MotorTestSample& s, std::int64_t now_us,
                                        bool disarmed) {
  if (s.motor == 0) {
    end();  // a request to stop is always obeyed
    return MotorTestResult::kOk;
  }
  if (!disarmed) return MotorTestResult::kRefusedNotDisarmed;
  if (last_armed_setpoint_us_ != kNever &&
      now_us - last_armed_setpoint_us_ <= setpoint_timeout_us_) {
    return MotorTestResult::kRefusedArmedSetpoint;
  }
  if (s.motor < 0 || s.motor > motors_) return MotorTestResult::kRefusedMotor;
  if (s.throttle < 0.0 || s.throttle > settings_.max_throttle) {
    return MotorTestResult::kRefusedThrottle;
  }
  if (s.duration_s <= 0.0 || s.duration_s > settings_.max_seconds) {
    return MotorTestResult::kRefusedDuration;
  }
  motor_ = s.motor - 1;
  throttle_ = s.throttle;
  end_us_ = now_us + seconds_to_us(s.duration_s);
  changed_ = true;
  return MotorTestResult::kOk;
}

void MotorTestRunner::spin(const Mixer& mixer, MixerOutput& out) const {
  mixer.disarm(out);
  const int n = mixer.motors();
  MotorVector command = MotorVector::Zero(n);
  command[motor_] = throttle_;
  const MotorMask all = (MotorMask{1} << n) - 1;
  const MotorMask others = all & ~(MotorMask{1} << motor_);
  mixer.output_stage().armed(command, out.output, out.direction, 0.0, false, others);
  out.command = command;
  out.armed = false;
}

}  // namespace motormix::loop
