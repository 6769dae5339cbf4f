// The units the control loop is composed of, each on its own: one freshness
// rule for every input, arming and failsafe, the motor test, spool-up, the
// failure set and the counters' sum. ControlLoop's own tests check them
// together.

#include "loop/arming.hpp"
#include "loop/counters.hpp"
#include "loop/failure_set.hpp"
#include "loop/latest_input.hpp"
#include "loop/motor_test_runner.hpp"
#include "loop/spool_up.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

namespace motormix::test {
namespace {

using loop::Arming;
using loop::FailsafeReason;
using loop::LoopState;
using loop::MotorTestResult;

TEST(LatestInput, FreshUpToItsTimeoutInclusiveAndAgesFromReceiveTime) {
  loop::LatestInput<loop::PidSample> pid;
  EXPECT_FALSE(pid.any());
  EXPECT_FALSE(pid.fresh(0, 100 * kMs));
  EXPECT_EQ(pid.age_ms(5 * kMs), -1.0);
  EXPECT_EQ(pid.last_utime(), loop::kNever);
  EXPECT_EQ(pid.utime_or_zero(), 0);
  pid.accept(loop::PidSample{42, 0.1, 0.2, 0.3}, 10 * kMs);
  EXPECT_TRUE(pid.fresh(110 * kMs, 100 * kMs));
  EXPECT_FALSE(pid.fresh(110 * kMs + 1, 100 * kMs));
  EXPECT_DOUBLE_EQ(pid.age_ms(35 * kMs), 25.0);
  EXPECT_EQ(pid.last_utime(), 42);
  EXPECT_EQ(pid.sample().pitch, 0.2);
}

TEST(LatestInput, NoOverflowAtTheExtremesOfTheClock) {
  loop::LatestInput<loop::BatterySample> b;
  EXPECT_FALSE(b.fresh(std::numeric_limits<std::int64_t>::max(), 1));
  b.accept(loop::BatterySample{1, 12.0}, std::numeric_limits<std::int64_t>::min() + 1);
  EXPECT_TRUE(b.any());
}

Arming::Inputs fresh_inputs(bool armed, double throttle = 0.0) {
  Arming::Inputs in;
  in.setpoint_fresh = true;
  in.pid_fresh = true;
  in.setpoint_armed = armed;
  in.throttle = throttle;
  return in;
}

TEST(Arming, NeedsADisarmedSetpointFirstThenArms) {
  Arming a(0.1);
  const Arming::Events first = a.update(fresh_inputs(true), 0);
  EXPECT_EQ(a.state(), LoopState::kDisarmed);  // started while "armed": no jump
  // Refused with its reason, once per request (the node logs it).
  EXPECT_TRUE(first.arming_refused);
  EXPECT_EQ(first.refusal, Arming::Refusal::kNotDisarmedFirst);
  EXPECT_FALSE(a.update(fresh_inputs(true), 0).arming_refused);
  a.on_setpoint(false);
  a.update(fresh_inputs(false), 1);
  a.on_setpoint(true);
  a.update(fresh_inputs(true), 2);
  EXPECT_EQ(a.state(), LoopState::kArmed);
  EXPECT_EQ(a.armed_since_us(), 2);
}

TEST(Arming, RefusesHighThrottleOncePerRequest) {
  Arming a(0.1);
  a.on_setpoint(false);
  const Arming::Events high = a.update(fresh_inputs(true, 0.5), 0);
  EXPECT_TRUE(high.arming_refused);
  EXPECT_EQ(high.refusal, Arming::Refusal::kThrottleHigh);
  EXPECT_FALSE(a.update(fresh_inputs(true, 0.5), 1).arming_refused);
  EXPECT_EQ(a.state(), LoopState::kDisarmed);
  a.update(fresh_inputs(false), 2);                                   // the request ends
  EXPECT_TRUE(a.update(fresh_inputs(true, -0.5), 3).arming_refused);  // |throttle|
}

TEST(Arming, FailsafeReasonsInOrderOfPrecedenceAndTheWayOut) {
  for (int which = 0; which < 3; ++which) {
    Arming a(1.0);
    a.on_setpoint(false);
    a.update(fresh_inputs(true), 0);
    ASSERT_EQ(a.state(), LoopState::kArmed);
    Arming::Inputs in = fresh_inputs(true);
    in.pid_fresh = false;
    if (which >= 1) in.setpoint_fresh = false;
    if (which >= 2) in.stalled = true;
    EXPECT_TRUE(a.update(in, 10).failsafe_entered);
    EXPECT_EQ(a.state(), LoopState::kFailsafe);
    const FailsafeReason expected[] = {FailsafeReason::kPidStale, FailsafeReason::kSetpointStale,
                                       FailsafeReason::kLoopStalled};
    EXPECT_EQ(a.reason(), expected[which]);
    EXPECT_EQ(a.failsafe_since_us(), 10);
    // Fresh armed inputs do not bring it back; a disarmed setpoint does,
    // and arming again needs that setpoint to have been accepted.
    EXPECT_FALSE(a.update(fresh_inputs(true), 11).failsafe_entered);
    EXPECT_EQ(a.state(), LoopState::kFailsafe);
    a.update(fresh_inputs(false), 12);
    EXPECT_EQ(a.state(), LoopState::kDisarmed);
    EXPECT_EQ(a.reason(), FailsafeReason::kNone);
    a.update(fresh_inputs(true), 13);
    EXPECT_EQ(a.state(), LoopState::kDisarmed);  // no disarmed setpoint accepted since
    a.on_setpoint(false);
    a.update(fresh_inputs(true), 14);
    EXPECT_EQ(a.state(), LoopState::kArmed);
  }
}

TEST(Arming, ADisarmedSetpointDisarms) {
  Arming a(1.0);
  a.on_setpoint(false);
  a.update(fresh_inputs(true), 0);
  EXPECT_FALSE(a.update(fresh_inputs(false), 1).failsafe_entered);
  EXPECT_EQ(a.state(), LoopState::kDisarmed);
}

class MotorTestRunnerTest : public ::testing::Test {
 protected:
  config::Config config_ = config::load_config_file(source_path("config/quad_x.yaml"));
  Mixer mixer_ = config::build_mixer(config_);
  config::MotorTestSettings settings_ = [] {
    config::MotorTestSettings s;
    s.enabled = true;
    s.max_throttle = 0.3;
    s.max_seconds = 5.0;
    return s;
  }();
  loop::MotorTestRunner runner_{settings_, 4, 100 * kMs};
  int future_asked_ = 0;
  MotorTestResult ask(int motor, double throttle, double seconds, std::int64_t now,
                      bool disarmed = true, std::int64_t utime = 0) {
    if (utime == 0) utime = next_utime_ += 1000;
    return runner_.request(loop::MotorTestSample{utime, motor, throttle, seconds}, now, disarmed,
                           [&](std::int64_t) {
                             ++future_asked_;
                             return false;
                           });
  }
  std::int64_t next_utime_ = 1'000'000;
};

TEST_F(MotorTestRunnerTest, RunsOneMotorAloneUntilItsDuration) {
  EXPECT_EQ(ask(2, 0.2, 1.0, 0), MotorTestResult::kOk);
  EXPECT_TRUE(runner_.running());
  EXPECT_EQ(runner_.motor(), 1);
  EXPECT_TRUE(runner_.take_changed());
  EXPECT_FALSE(runner_.take_changed());
  MixerOutput out;
  mixer_.disarm(out);
  runner_.spin(mixer_, out);
  EXPECT_FALSE(out.armed);
  for (int i = 0; i < 4; ++i) {
    if (i == 1) {
      EXPECT_GT(out.output[i], config_.outputs[i].min);
    } else {
      EXPECT_EQ(out.output[i], config_.outputs[i].disarmed);
    }
  }
  runner_.expire(999 * kMs, true);
  EXPECT_TRUE(runner_.running());
  runner_.expire(1000 * kMs, true);
  EXPECT_FALSE(runner_.running());
  EXPECT_TRUE(runner_.take_changed());
}

TEST_F(MotorTestRunnerTest, EachRefusalHasItsReason) {
  EXPECT_EQ(ask(1, 0.2, 1.0, 0, /*disarmed=*/false), MotorTestResult::kRefusedNotDisarmed);
  EXPECT_EQ(ask(5, 0.2, 1.0, 0), MotorTestResult::kRefusedMotor);
  EXPECT_EQ(ask(-1, 0.2, 1.0, 0), MotorTestResult::kRefusedMotor);
  EXPECT_EQ(ask(1, 0.31, 1.0, 0), MotorTestResult::kRefusedThrottle);
  EXPECT_EQ(ask(1, -0.01, 1.0, 0), MotorTestResult::kRefusedThrottle);
  EXPECT_EQ(ask(1, 0.2, 0.0, 0), MotorTestResult::kRefusedDuration);
  EXPECT_EQ(ask(1, 0.2, 5.01, 0), MotorTestResult::kRefusedDuration);
  const int asked = future_asked_;
  EXPECT_EQ(ask(1, std::nan(""), 1.0, 0), MotorTestResult::kRefusedInvalid);
  EXPECT_EQ(future_asked_, asked);  // the clock is not asked about a non-finite request
  runner_.on_armed_setpoint(10 * kMs);
  EXPECT_EQ(ask(1, 0.2, 1.0, 110 * kMs), MotorTestResult::kRefusedArmedSetpoint);
  EXPECT_EQ(ask(1, 0.2, 1.0, 110 * kMs + 1), MotorTestResult::kOk);
  EXPECT_TRUE(runner_.running());
  EXPECT_EQ(runner_.last_result(), MotorTestResult::kOk);
}

TEST_F(MotorTestRunnerTest, OutOfOrderRefusedUnlessAPublisherRestart) {
  EXPECT_EQ(ask(1, 0.2, 1.0, 0, true, 5'000'000), MotorTestResult::kOk);
  EXPECT_EQ(ask(1, 0.2, 1.0, 0, true, 5'000'000), MotorTestResult::kRefusedInvalid);
  EXPECT_EQ(ask(1, 0.2, 1.0, 0, true, 4'500'000), MotorTestResult::kRefusedInvalid);
  EXPECT_EQ(ask(1, 0.2, 1.0, 0, true, 5'000'000 - loop::kPublisherRestartUs), MotorTestResult::kOk);
  EXPECT_EQ(runner_.last_request_utime(), 5'000'000 - loop::kPublisherRestartUs);
}

TEST_F(MotorTestRunnerTest, DisabledRefusesEverythingAndStopAlwaysObeyed) {
  config::MotorTestSettings disabled = settings_;
  disabled.enabled = false;
  loop::MotorTestRunner r(disabled, 4, 100 * kMs);
  EXPECT_EQ(
      r.request(loop::MotorTestSample{1, 1, 0.1, 1.0}, 0, true, [](std::int64_t) { return false; }),
      MotorTestResult::kRefusedDisabled);
  EXPECT_EQ(ask(3, 0.2, 1.0, 0), MotorTestResult::kOk);
  EXPECT_EQ(ask(0, 0.0, 0.0, 0, /*disarmed=*/false), MotorTestResult::kOk);
  EXPECT_FALSE(runner_.running());
  EXPECT_EQ(ask(3, 0.2, 1.0, 0), MotorTestResult::kOk);
  runner_.expire(1, /*disarmed=*/false);  // the loop armed: the test ends
  EXPECT_FALSE(runner_.running());
}

TEST(SpoolUpRamp, RampsLinearlyAndBlendsFromTheStopValueInsideTheRange) {
  const loop::SpoolUp spool(2'000'000);
  EXPECT_EQ(spool.ramp(0), 0.0);
  EXPECT_DOUBLE_EQ(spool.ramp(500'000), 0.25);
  EXPECT_EQ(spool.ramp(2'000'000), 1.0);
  EXPECT_EQ(loop::SpoolUp(0).ramp(0), 1.0);  // none configured

  // disarmed 900 sits below min 1000: the ramp starts at 1000.
  const config::Config config = config::load_config_file(
      source_path("config/quad_x.yaml"), {"output.disarmed=900", "output.min=1000"});
  const Mixer mixer = config::build_mixer(config);
  MixerOutput out;
  mixer.disarm(out);
  for (int i = 0; i < 4; ++i) out.output[i] = 1600.0;
  out.failed = 0b0100;
  out.output[2] = 900.0;  // a failed motor keeps its stop value
  loop::SpoolUp::blend(mixer.output_stage(), 0.5, out);
  EXPECT_DOUBLE_EQ(out.output[0], 1300.0);
  EXPECT_DOUBLE_EQ(out.output[2], 900.0);
}

TEST(FailureSet, ConfiguredAndReportedAddUpWithinTheMotors) {
  const config::Config config = config::load_config_file(source_path("config/hexa_x.yaml"));
  const Mixer mixer = config::build_mixer(config);
  loop::FailureSet set(0b000001, 6);
  EXPECT_EQ(set.in_force(), 0b000001U);
  set.set_reported(0b1000010);  // bit 6: no such motor
  EXPECT_EQ(set.in_force(), 0b000011U);
  EXPECT_EQ(set.report(mixer).handling, mixer.failure_report(0b000011).handling);
  set.set_reported(0);  // a report that clears leaves the configured one
  EXPECT_EQ(set.in_force(), 0b000001U);
  EXPECT_EQ(set.report(mixer).handling, mixer.failure_report(0b000001).handling);
}

TEST(Counters, SumCoversEveryCounter) {
  loop::Counters a;
  loop::Counters b;
  std::int64_t v = 1;
  for (const auto field : loop::Counters::kAll) b.*field = v++;
  a += b;
  a += b;
  v = 1;
  for (const auto field : loop::Counters::kAll) EXPECT_EQ(a.*field, 2 * v++);
}

}  // namespace
}  // namespace motormix::test
