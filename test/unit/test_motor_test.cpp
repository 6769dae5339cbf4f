// Motor tests in the control loop, with injected time: which requests are
// obeyed, what the outputs do while one runs, and every way it ends.

#include "loop/control_loop.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace motormix::test {
namespace {

using loop::ControlLoop;
using loop::LoopState;
using loop::MotorTestResult;
using loop::MotorTestSample;
using loop::PidSample;
using loop::SetpointSample;

constexpr double kDisarmedUs = 900.0;  // config/quad_x.yaml output.disarmed
constexpr std::int64_t kSecond = 1'000'000;

class MotorTestLoop : public ::testing::Test {
 protected:
  config::Config config_ = config::load_config_file(source_path("config/quad_x.yaml"));
  ControlLoop loop_{config_, config::build_mixer(config_)};
  std::int64_t utime_ = 1'700'000'000'000'000;

  MotorTestResult request(std::int64_t now, int motor, double throttle, double seconds) {
    return loop_.on_motor_test(MotorTestSample{utime_ += 1000, motor, throttle, seconds}, now,
                               kWall);
  }
  void setpoint(std::int64_t now, bool armed) {
    loop_.on_setpoint(SetpointSample{utime_ += 1000, 0.0, 0.0, armed}, now, kWall);
    loop_.on_pid(PidSample{utime_ += 1000, 0.0, 0.0, 0.0}, now, kWall);
  }
  // The output of one channel at `command` through the configured stage:
  // linearized, then mapped above idle, then onto the PWM range.
  double stage_output(double command) const {
    const OutputChannel& ch = config_.outputs[0];
    const double x =
        ch.idle + (1.0 - ch.idle) * OutputStage::linearize(command, ch.thrust_model_factor);
    return ch.min + x * (ch.max - ch.min);
  }
};

TEST_F(MotorTestLoop, SpinsTheRightMotorAloneWithTheOutputsDisarmed) {
  ASSERT_EQ(request(0, 3, 0.1, 1.0), MotorTestResult::kOk);
  const loop::CycleResult& r = loop_.cycle(10 * kMs);
  EXPECT_EQ(r.state, LoopState::kDisarmed);
  EXPECT_FALSE(r.mix.armed);
  EXPECT_EQ(r.motor_test, 2);
  EXPECT_TRUE(r.motor_test_changed);
  for (int i = 0; i < 4; ++i) {
    if (i == 2) {
      EXPECT_NEAR(r.mix.output[i], stage_output(0.1), kExact);
      EXPECT_GT(r.mix.output[i], config_.outputs[0].min);
    } else {
      EXPECT_EQ(r.mix.output[i], kDisarmedUs) << "motor " << i + 1;
    }
  }
  EXPECT_EQ(loop_.counters().motor_tests_started, 1);
}

TEST_F(MotorTestLoop, EndsAtItsDurationWithDisarmedOutputs) {
  ASSERT_EQ(request(0, 1, 0.1, 0.5), MotorTestResult::kOk);
  EXPECT_EQ(loop_.cycle(kSecond / 2 - 1).motor_test, 0);
  const loop::CycleResult& r = loop_.cycle(kSecond / 2);
  EXPECT_EQ(r.motor_test, -1);
  EXPECT_TRUE(r.motor_test_changed);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(r.mix.output[i], kDisarmedUs);
  EXPECT_FALSE(loop_.cycle(kSecond).motor_test_changed);
}

TEST_F(MotorTestLoop, RefusedWhileArmedAndSoonAfterAnArmedSetpoint) {
  setpoint(0, false);
  loop_.cycle(0);
  setpoint(kMs, true);
  ASSERT_EQ(loop_.cycle(kMs).state, LoopState::kArmed);
  EXPECT_EQ(request(2 * kMs, 1, 0.1, 1.0), MotorTestResult::kRefusedNotDisarmed);
  setpoint(10 * kMs, false);
  ASSERT_EQ(loop_.cycle(10 * kMs).state, LoopState::kDisarmed);
  // The last armed setpoint arrived at 1 ms; the setpoint timeout is 100 ms.
  EXPECT_EQ(request(50 * kMs, 1, 0.1, 1.0), MotorTestResult::kRefusedArmedSetpoint);
  EXPECT_EQ(request(102 * kMs, 1, 0.1, 1.0), MotorTestResult::kOk);
  EXPECT_EQ(loop_.counters().motor_tests_refused, 2);
}

TEST_F(MotorTestLoop, RefusesWhatIsOutOfBounds) {
  EXPECT_EQ(request(0, 1, 0.16, 1.0), MotorTestResult::kRefusedThrottle);  // max_throttle 0.15
  EXPECT_EQ(request(0, 1, -0.01, 1.0), MotorTestResult::kRefusedThrottle);
  EXPECT_EQ(request(0, 1, 0.1, 3.5), MotorTestResult::kRefusedDuration);  // max_seconds 3
  EXPECT_EQ(request(0, 1, 0.1, 0.0), MotorTestResult::kRefusedDuration);
  EXPECT_EQ(request(0, 5, 0.1, 1.0), MotorTestResult::kRefusedMotor);
  EXPECT_EQ(request(0, -1, 0.1, 1.0), MotorTestResult::kRefusedMotor);
  EXPECT_EQ(request(0, 1, std::nan(""), 1.0), MotorTestResult::kRefusedInvalid);
  EXPECT_EQ(request(0, 1, 0.1, std::numeric_limits<double>::infinity()),
            MotorTestResult::kRefusedInvalid);
  EXPECT_EQ(
      loop_.on_motor_test(MotorTestSample{utime_ - 5000, 1, 0.1, 1.0}, 0, kWall),  // went back
      MotorTestResult::kRefusedInvalid);
  EXPECT_EQ(loop_.cycle(kMs).motor_test, -1);
  EXPECT_EQ(loop_.counters().motor_tests_refused, 9);
  EXPECT_EQ(loop_.counters().motor_tests_started, 0);
}

TEST_F(MotorTestLoop, EndsAtTheFirstArmedSetpoint) {
  setpoint(0, false);
  loop_.cycle(0);
  ASSERT_EQ(request(kSecond, 2, 0.1, 2.0), MotorTestResult::kOk);
  ASSERT_EQ(loop_.cycle(kSecond).motor_test, 1);
  setpoint(kSecond + kMs, true);
  const loop::CycleResult& r = loop_.cycle(kSecond + kMs);
  EXPECT_EQ(r.motor_test, -1);
  EXPECT_TRUE(r.motor_test_changed);
  EXPECT_EQ(r.state, LoopState::kArmed);  // and the pilot arms as usual
}

TEST_F(MotorTestLoop, ANewTestReplacesTheRunningOneAndMotorZeroStopsIt) {
  ASSERT_EQ(request(0, 1, 0.1, 2.0), MotorTestResult::kOk);
  ASSERT_EQ(loop_.cycle(kMs).motor_test, 0);
  ASSERT_EQ(request(2 * kMs, 4, 0.12, 2.0), MotorTestResult::kOk);
  const loop::CycleResult& r = loop_.cycle(3 * kMs);
  EXPECT_EQ(r.motor_test, 3);
  EXPECT_EQ(r.mix.output[0], kDisarmedUs);
  EXPECT_NEAR(r.mix.output[3], stage_output(0.12), kExact);
  ASSERT_EQ(request(4 * kMs, 0, 0.0, 0.0), MotorTestResult::kOk);
  EXPECT_EQ(loop_.cycle(5 * kMs).motor_test, -1);
}

TEST(MotorTestSettings, DisabledRefusesEveryRequestAndBoundsAreValidated) {
  const config::Config off =
      config::load_config_file(source_path("config/quad_x.yaml"), {"motor_test.enabled=false"});
  ControlLoop loop(off, config::build_mixer(off));
  EXPECT_EQ(loop.on_motor_test(MotorTestSample{1, 1, 0.1, 1.0}, 0, kWall),
            MotorTestResult::kRefusedDisabled);
  EXPECT_THROW(
      config::load_config_file(source_path("config/quad_x.yaml"), {"motor_test.max_throttle=1.5"}),
      config::ConfigError);
  EXPECT_THROW(
      config::load_config_file(source_path("config/quad_x.yaml"), {"channels.motor_test=PID"}),
      config::ConfigError);
}

}  // namespace
}  // namespace motormix::test

namespace motormix::test {
namespace {

// Spool-up: the ramp after arming, with injected time.
class SpoolUp : public ::testing::Test {
 protected:
  // quad_x.yaml: disarmed 900 us, min 1000, idle 0.05, spool_up_s 0.5 by default.
  config::Config config_ =
      config::load_config_file(source_path("config/quad_x.yaml"), {"inputs.arm_max_throttle=1"});
  ControlLoop loop_{config_, config::build_mixer(config_)};
  std::int64_t utime_ = 1'700'000'000'000'000;
  void inputs(std::int64_t now, bool armed, double throttle, double roll = 0.0) {
    loop_.on_setpoint(SetpointSample{utime_ += 1000, throttle, 0.0, armed}, now, kWall);
    loop_.on_pid(PidSample{utime_ += 1000, roll, 0.0, 0.0}, now, kWall);
  }
  // Arms at `t0` with constant inputs; returns each motor's output every 5 ms.
  std::vector<MotorVector> fly(std::int64_t t0, double throttle, double roll, std::int64_t until) {
    inputs(t0 - kMs, false, throttle, roll);
    loop_.cycle(t0 - kMs);
    std::vector<MotorVector> outputs;
    for (std::int64_t t = t0; t <= until; t += 5 * kMs) {
      inputs(t, true, throttle, roll);
      outputs.push_back(loop_.cycle(t).mix.output);
    }
    return outputs;
  }
};

TEST_F(SpoolUp, DefaultsToHalfASecondForAircraftAndNoneForWheels) {
  EXPECT_DOUBLE_EQ(config_.spool_up_s, 0.5);
  EXPECT_DOUBLE_EQ(config::load_config_file(source_path("config/diff_drive.yaml")).spool_up_s, 0.0);
}

TEST_F(SpoolUp, OutputsRiseMonotonicallyFromDisarmedToTheMixedValue) {
  const std::vector<MotorVector> out = fly(0, 0.5, 0.1, 800 * kMs);
  const config::Config flat =
      config::load_config_file(source_path("config/quad_x.yaml"), {"output.spool_up_s=0"});
  MixerOutput mixed;
  config::build_mixer(flat).mix(AxisVector(0.1, 0.0, 0.0, 0.5), mixed);
  for (int i = 0; i < 4; ++i) {
    // From the disarmed value taken into the range: the ESC's zero, 1000 us.
    EXPECT_NEAR(out.front()[i], 1000.0, kExact) << "the first armed cycle starts from stopped";
    for (std::size_t k = 1; k < out.size(); ++k) {
      EXPECT_GE(out[k][i], out[k - 1][i] - kExact) << "motor " << i + 1 << " at " << 5 * k << " ms";
      EXPECT_LE(out[k][i], mixed.output[i] + kExact) << "never above its mixed value";
    }
    EXPECT_NEAR(out.back()[i], mixed.output[i], kExact) << "spooled up: exactly the mix";
  }
  // Halfway, every output is below its mixed value and above idle.
  const MotorVector& half = out[50];  // 250 ms
  for (int i = 0; i < 4; ++i) {
    EXPECT_LT(half[i], mixed.output[i]);
    EXPECT_GT(half[i], 1000.0);
  }
}

TEST_F(SpoolUp, ReportedAndRestartedAfterADisarm) {
  // A cycle every 5 ms (a longer gap is a stalled loop), armed from 5 ms.
  const auto at = [&](std::int64_t t, bool armed) -> const loop::CycleResult& {
    inputs(t, armed, 0.0);
    return loop_.cycle(t);
  };
  at(0, false);
  const loop::CycleResult& r = at(5 * kMs, true);
  EXPECT_EQ(r.state, LoopState::kArmed);
  EXPECT_TRUE(r.spooling_up);
  EXPECT_DOUBLE_EQ(r.spool_up, 0.0);
  std::int64_t t = 5 * kMs;
  while (t < 255 * kMs) at(t += 5 * kMs, true);
  EXPECT_NEAR(loop_.last().spool_up, 0.5, 1e-12);
  while (t < 600 * kMs) at(t += 5 * kMs, true);
  EXPECT_FALSE(loop_.last().spooling_up);
  EXPECT_DOUBLE_EQ(loop_.last().spool_up, 1.0);
  EXPECT_EQ(at(t += 5 * kMs, false).spool_up, 0.0);         // disarmed
  const loop::CycleResult& again = at(t += 5 * kMs, true);  // and armed again: from the start
  EXPECT_EQ(again.state, LoopState::kArmed);
  EXPECT_TRUE(again.spooling_up);
  EXPECT_DOUBLE_EQ(again.spool_up, 0.0);
}

}  // namespace
}  // namespace motormix::test
