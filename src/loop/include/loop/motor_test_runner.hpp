#pragma once
// The motor test: one motor spun alone through the output stage while the
// outputs stay disarmed (armed = false), for bring-up.
//
// A request is obeyed only when motor_test.enabled, the loop is disarmed, no
// armed setpoint arrived within the setpoint timeout, and throttle and
// duration are within motor_test.max_throttle and max_seconds. A test ends
// at its duration, at the first armed setpoint, when a new test replaces
// it, when the loop leaves the disarmed state, or on request (motor 0).
// Every refusal has its reason (mixer_status_t MOTOR_TEST_REFUSED_*).

#include <motormix/enum_names.hpp>
#include "loop/input_samples.hpp"
#include "loop/latest_input.hpp"
#include "loop/message_checks.hpp"

#include <motormix/config/config.hpp>
#include <motormix/mixer.hpp>

#include <cmath>
#include <cstdint>

namespace motormix::loop {

enum class MotorTestResult : std::int8_t {
  kOk = 0,
  kRefusedDisabled = 1,
  kRefusedNotDisarmed = 2,
  kRefusedArmedSetpoint = 3,
  kRefusedThrottle = 4,
  kRefusedDuration = 5,
  kRefusedMotor = 6,
  kRefusedInvalid = 7,
};
inline constexpr EnumName<MotorTestResult> kMotorTestResultNames[] = {
    {MotorTestResult::kOk, "ok"},
    {MotorTestResult::kRefusedDisabled, "motor tests are disabled (motor_test.enabled: false)"},
    {MotorTestResult::kRefusedNotDisarmed, "the mixer is armed or in failsafe"},
    {MotorTestResult::kRefusedArmedSetpoint, "an armed setpoint arrived within the input timeout"},
    {MotorTestResult::kRefusedThrottle, "throttle outside 0..motor_test.max_throttle"},
    {MotorTestResult::kRefusedDuration, "duration outside 0..motor_test.max_seconds"},
    {MotorTestResult::kRefusedMotor, "no such motor"},
    {MotorTestResult::kRefusedInvalid, "not finite, out of order or from the future"},
};
inline const char* to_string(MotorTestResult value) {
  return name_in(kMotorTestResultNames, value);
}

class MotorTestRunner {
 public:
  MotorTestRunner(const config::MotorTestSettings& settings, int motors,
                  std::int64_t setpoint_timeout_us)
      : settings_(settings), motors_(motors), setpoint_timeout_us_(setpoint_timeout_us) {}

  // An armed setpoint arrived: the pilot wants to fly, so no motor spins on
  // its own any more, and none starts for a setpoint timeout.
  void on_armed_setpoint(std::int64_t now_us) {
    last_armed_setpoint_us_ = now_us;
    end();
  }

  // A request at now_us while the loop is (or is not) disarmed.
  // from_future(utime) is asked only for an enabled, finite request, and
  // counts what it refuses.
  template <typename FromFuture>
  MotorTestResult request(const MotorTestSample& s, std::int64_t now_us, bool disarmed,
                          FromFuture&& from_future) {
    MotorTestResult r = MotorTestResult::kOk;
    if (!settings_.enabled) {
      r = MotorTestResult::kRefusedDisabled;
    } else if (!std::isfinite(s.throttle) || !std::isfinite(s.duration_s) || from_future(s.utime) ||
               out_of_order(s.utime)) {
      r = MotorTestResult::kRefusedInvalid;
    } else {
      r = decide(s, now_us, disarmed);
    }
    if (r != MotorTestResult::kRefusedInvalid) last_utime_ = s.utime;
    last_request_utime_ = s.utime;
    last_result_ = r;
    return r;
  }

  // Once per cycle: a test ends at its end time or when the loop is not
  // disarmed.
  void expire(std::int64_t now_us, bool disarmed) {
    if (running() && (!disarmed || now_us >= end_us_)) end();
  }
  void end() {
    if (!running()) return;
    motor_ = -1;
    changed_ = true;
  }

  // The running test's motor alone through the output stage (its idle,
  // linearization, limits and direction pin), every other output at its
  // disarmed value; armed stays false.
  void spin(const Mixer& mixer, MixerOutput& out) const;

  bool running() const { return motor_ >= 0; }
  int motor() const { return motor_; }  // 0-based, -1 when none
  double throttle() const { return running() ? throttle_ : 0.0; }
  // A test started or ended since the last call.
  bool take_changed() {
    const bool c = changed_;
    changed_ = false;
    return c;
  }
  std::int64_t last_request_utime() const { return last_request_utime_; }
  MotorTestResult last_result() const { return last_result_; }

 private:
  bool out_of_order(std::int64_t utime) const;
  MotorTestResult decide(const MotorTestSample& s, std::int64_t now_us, bool disarmed);

  config::MotorTestSettings settings_;
  int motors_;
  std::int64_t setpoint_timeout_us_;
  std::int64_t last_armed_setpoint_us_ = kNever;  // receive time of the last armed setpoint
  std::int64_t last_utime_ = kNever;              // of the last valid request
  int motor_ = -1;                                // running test, 0-based
  double throttle_ = 0.0;
  std::int64_t end_us_ = 0;
  bool changed_ = false;
  std::int64_t last_request_utime_ = 0;
  MotorTestResult last_result_ = MotorTestResult::kOk;
};

}  // namespace motormix::loop
