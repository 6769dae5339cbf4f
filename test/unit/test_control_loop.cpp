// The control loop's decisions with injected time: arming, staleness,
// failsafe, recovery and rejection accounting.

#include "loop/control_loop.hpp"
#include "messages/messages.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <limits>

namespace motormix::test {
namespace {

using loop::ControlLoop;
using loop::FailsafeReason;
using loop::LoopState;
using loop::PidSample;
using loop::Rejection;
using loop::SetpointSample;

class ControlLoopTest : public ::testing::Test {
 protected:
  // These tests arm at half throttle and check the outputs from the first
  // armed cycle; the arming check and the spool-up ramp have tests of their own.
  config::Config config_ = config::load_config_file(
      source_path("config/team_quad.yaml"), {"inputs.arm_max_throttle=1", "output.spool_up_s=0"});
  ControlLoop loop_{config_, config::build_mixer(config_)};
  std::int64_t utime_ = 1'700'000'000'000'000;

  void setpoint(std::int64_t now, bool armed, double throttle = 0.5, double yaw = 0.0) {
    ASSERT_EQ(loop_.on_setpoint(SetpointSample{utime_ += 1000, throttle, yaw, armed}, now, kWall),
              Rejection::kNone);
  }
  void pid(std::int64_t now, double roll = 0.0, double pitch = 0.0) {
    ASSERT_EQ(loop_.on_pid(PidSample{utime_ += 1000, roll, pitch, 0.0}, now, kWall),
              Rejection::kNone);
  }
  void arm(std::int64_t now) {
    setpoint(now, false);
    pid(now);
    ASSERT_EQ(loop_.cycle(now).state, LoopState::kDisarmed);
    setpoint(now, true);
    ASSERT_EQ(loop_.cycle(now).state, LoopState::kArmed);
  }
  static void expect_disarmed_outputs(const loop::CycleResult& r) {
    EXPECT_FALSE(r.mix.armed);
    for (int i = 0; i < r.mix.output.size(); ++i) EXPECT_EQ(r.mix.output[i], 1000.0);
  }
};

TEST_F(ControlLoopTest, DisarmedUntilFirstValidSetpoint) {
  const auto& r = loop_.cycle(0);
  EXPECT_EQ(r.state, LoopState::kDisarmed);
  EXPECT_TRUE(r.setpoint_stale);
  EXPECT_TRUE(r.pid_stale);
  expect_disarmed_outputs(r);
}

TEST_F(ControlLoopTest, ArmingNeedsAnExplicitTransition) {
  // A mixer that starts while the setpoint already says "armed" stays
  // disarmed: no motor jump.
  setpoint(0, true);
  pid(0);
  EXPECT_EQ(loop_.cycle(0).state, LoopState::kDisarmed);
  setpoint(1 * kMs, false);
  EXPECT_EQ(loop_.cycle(1 * kMs).state, LoopState::kDisarmed);
  setpoint(2 * kMs, true);
  const auto& r = loop_.cycle(2 * kMs);
  EXPECT_EQ(r.state, LoopState::kArmed);
  EXPECT_TRUE(r.state_changed);
  EXPECT_TRUE(r.mix.armed);
  EXPECT_NEAR(r.mix.output[0], 1150.0 + 0.5 * 0.6 * 774.0, kExact);
}

TEST_F(ControlLoopTest, ArmingNeedsAFreshPid) {
  setpoint(0, false);
  setpoint(1 * kMs, true);
  EXPECT_EQ(loop_.cycle(1 * kMs).state, LoopState::kDisarmed);
  pid(2 * kMs);
  EXPECT_EQ(loop_.cycle(2 * kMs).state, LoopState::kArmed);
}

TEST_F(ControlLoopTest, OutputsFollowTheInputsInForce) {
  arm(0);
  pid(1 * kMs, 0.5, 0.0);
  setpoint(1 * kMs, true, 0.0, 0.0);
  const auto& r = loop_.cycle(1 * kMs);
  EXPECT_NEAR(r.mix.output[0], 1246.75, kExact);
  EXPECT_NEAR(r.mix.output[1], 1150.0, kExact);
  EXPECT_EQ(r.pid_utime, utime_ - 1000);
  EXPECT_EQ(r.setpoint_utime, utime_);
}

TEST_F(ControlLoopTest, StaleSetpointFailsSafeAtTheTimeout) {
  arm(0);
  pid(90 * kMs);
  EXPECT_EQ(loop_.cycle(100 * kMs).state, LoopState::kArmed);  // exactly at the timeout: fresh
  pid(100 * kMs);
  const auto& r = loop_.cycle(100 * kMs + 1);
  EXPECT_EQ(r.state, LoopState::kFailsafe);
  EXPECT_EQ(r.reason, FailsafeReason::kSetpointStale);
  EXPECT_TRUE(r.setpoint_stale);
  expect_disarmed_outputs(r);
  EXPECT_EQ(loop_.counters().failsafe_events, 1);
}

TEST_F(ControlLoopTest, StalePidFailsSafe) {
  arm(0);
  for (std::int64_t t = 10 * kMs; t < 150 * kMs; t += 10 * kMs) {  // the loop ticking
    setpoint(t, true);
    loop_.cycle(t);
  }
  setpoint(150 * kMs, true);
  const auto& r = loop_.cycle(150 * kMs);
  EXPECT_EQ(r.state, LoopState::kFailsafe);
  EXPECT_EQ(r.reason, FailsafeReason::kPidStale);
  EXPECT_EQ(loop_.counters().failsafe_events, 1);
}

// A cycle later than the shorter input timeout after the previous one (the
// process was frozen) fails safe even when the inputs handled just before it
// look fresh; a cycle exactly at the timeout does not.
TEST_F(ControlLoopTest, StalledLoopFailsSafeEvenWithFreshInputs) {
  arm(0);
  setpoint(100 * kMs, true);
  pid(100 * kMs);
  EXPECT_EQ(loop_.cycle(100 * kMs).state, LoopState::kArmed);  // a gap of exactly the timeout
  setpoint(201 * kMs, true);
  pid(201 * kMs);
  const auto& r = loop_.cycle(201 * kMs);
  EXPECT_EQ(r.state, LoopState::kFailsafe);
  EXPECT_EQ(r.reason, FailsafeReason::kLoopStalled);
  expect_disarmed_outputs(r);
  // Leaving it is the usual way: disarmed, then armed again.
  setpoint(202 * kMs, false);
  EXPECT_EQ(loop_.cycle(202 * kMs).state, LoopState::kDisarmed);
  setpoint(203 * kMs, true);
  EXPECT_EQ(loop_.cycle(203 * kMs).state, LoopState::kArmed);
}

TEST_F(ControlLoopTest, RecoveryNeedsReArming) {
  arm(0);
  EXPECT_EQ(loop_.cycle(200 * kMs).state, LoopState::kFailsafe);
  // The publisher comes back still saying "armed": outputs stay disarmed.
  setpoint(300 * kMs, true);
  pid(300 * kMs);
  EXPECT_EQ(loop_.cycle(300 * kMs).state, LoopState::kFailsafe);
  expect_disarmed_outputs(loop_.last());
  setpoint(310 * kMs, false);
  pid(310 * kMs);
  EXPECT_EQ(loop_.cycle(310 * kMs).state, LoopState::kDisarmed);
  setpoint(320 * kMs, true);
  EXPECT_EQ(loop_.cycle(320 * kMs).state, LoopState::kArmed);
}

TEST_F(ControlLoopTest, DisarmFromTheSetpoint) {
  arm(0);
  setpoint(5 * kMs, false);
  const auto& r = loop_.cycle(5 * kMs);
  EXPECT_EQ(r.state, LoopState::kDisarmed);
  expect_disarmed_outputs(r);
  EXPECT_EQ(loop_.counters().failsafe_events, 0);
}

TEST_F(ControlLoopTest, RejectedMessagesAreCountedAndLeaveTheOldInputInForce) {
  arm(0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(loop_.on_pid(PidSample{utime_ + 1, nan, 0, 0}, 1 * kMs, kWall), Rejection::kNonFinite);
  EXPECT_EQ(loop_.on_pid(PidSample{utime_ + 2, 1.5, 0, 0}, 1 * kMs, kWall), Rejection::kOutOfRange);
  EXPECT_EQ(loop_.on_setpoint(SetpointSample{utime_ + 3, -0.1, 0, true}, 1 * kMs, kWall),
            Rejection::kOutOfRange);
  EXPECT_EQ(loop_.on_pid(PidSample{utime_ - 500'000, 0.2, 0, 0}, 1 * kMs, kWall),
            Rejection::kOutOfOrder);
  const auto& c = loop_.counters();
  EXPECT_EQ(c.rejected_nonfinite, 1);
  EXPECT_EQ(c.rejected_range, 2);
  EXPECT_EQ(c.rejected_out_of_order, 1);
  const auto& r = loop_.cycle(1 * kMs);
  EXPECT_EQ(r.state, LoopState::kArmed);
  EXPECT_NEAR(r.mix.output[0], 1150.0 + 0.3 * 774.0, kExact);  // roll still 0
  // The good inputs age out as usual despite the rejected traffic.
  EXPECT_EQ(loop_.cycle(150 * kMs).state, LoopState::kFailsafe);
}

TEST_F(ControlLoopTest, PublisherRestartWithEarlierClockIsAccepted) {
  arm(0);
  EXPECT_EQ(loop_.on_pid(PidSample{1000, 0.1, 0, 0}, 1 * kMs, kWall), Rejection::kNone);
}

TEST_F(ControlLoopTest, YawFromPidWhenConfigured) {
  config_.inputs.yaw_source = config::YawSource::kPid;
  ControlLoop loop(config_, config::build_mixer(config_));
  loop.on_setpoint(SetpointSample{1, 0.0, 1.0, false}, 0, kWall);
  loop.on_pid(PidSample{1, 0.0, 0.0, -1.0}, 0, kWall);
  loop.cycle(0);
  loop.on_setpoint(SetpointSample{2, 0.0, 1.0, true}, 0, kWall);
  const auto& r = loop.cycle(0);
  ASSERT_EQ(r.state, LoopState::kArmed);
  // Negative yaw from the pid: FR and RL get 15 %.
  EXPECT_NEAR(r.mix.command[1], 0.15, kExact);
  EXPECT_NEAR(r.mix.command[0], 0.0, kExact);
}

// A mixer started while its controller already says armed (or after a
// landing): refused, counted and said why in the cycle's result.
TEST(ArmingCheck, ArmedWithoutADisarmedSetpointFirstIsRefusedWithItsReason) {
  const config::Config c = team_quad_config();
  ControlLoop loop(c, config::build_mixer(c));
  loop.on_setpoint(SetpointSample{1, 0.0, 0, true}, 0, kWall);
  loop.on_pid(PidSample{1, 0, 0, 0}, 0, kWall);
  const auto& r = loop.cycle(0);
  EXPECT_EQ(r.state, LoopState::kDisarmed);
  EXPECT_EQ(r.arming_refused, loop::Arming::Refusal::kNotDisarmedFirst);
  const auto& later = loop.cycle(1 * kMs);
  EXPECT_EQ(later.arming_refused, loop::Arming::Refusal::kNone) << "said once";
  EXPECT_EQ(later.last_arming_refusal, loop::Arming::Refusal::kNotDisarmedFirst)
      << "the status keeps saying why";
  EXPECT_EQ(loop.counters().arming_refused, 1);
  EXPECT_EQ(loop.counters().arming_refused_not_disarmed_first, 1);
  EXPECT_EQ(loop.counters().arming_refused_throttle, 0);
}

TEST(ArmingCheck, RefusedWithThrottleUp) {
  const config::Config c = team_quad_config();  // default check: |throttle| <= 0.1
  ControlLoop loop(c, config::build_mixer(c));
  loop.on_setpoint(SetpointSample{1, 0.5, 0, false}, 0, kWall);
  loop.on_pid(PidSample{1, 0, 0, 0}, 0, kWall);
  loop.cycle(0);
  loop.on_setpoint(SetpointSample{2, 0.5, 0, true}, 1 * kMs, kWall);  // half throttle: refused
  EXPECT_EQ(loop.cycle(1 * kMs).state, LoopState::kDisarmed);
  EXPECT_EQ(loop.cycle(2 * kMs).state, LoopState::kDisarmed);
  EXPECT_EQ(loop.counters().arming_refused, 1);  // counted once per request
  EXPECT_EQ(loop.counters().arming_refused_throttle, 1);
  EXPECT_EQ(loop.cycle(2 * kMs).last_arming_refusal, loop::Arming::Refusal::kThrottleHigh);
  loop.on_setpoint(SetpointSample{3, 0.05, 0, true}, 3 * kMs, kWall);
  loop.on_pid(PidSample{3, 0, 0, 0}, 3 * kMs, kWall);
  const auto& armed = loop.cycle(3 * kMs);
  EXPECT_EQ(armed.state, LoopState::kArmed);
  EXPECT_EQ(armed.last_arming_refusal, loop::Arming::Refusal::kNone) << "cleared once armed";
}

TEST_F(ControlLoopTest, MessagesFromTheFutureAreRejected) {
  EXPECT_EQ(loop_.on_pid(PidSample{kWall + 2'000'000, 0, 0, 0}, 0, kWall), Rejection::kFromFuture);
  EXPECT_EQ(loop_.on_pid(PidSample{kWall + 500'000, 0, 0, 0}, 0, kWall), Rejection::kNone);
  EXPECT_EQ(loop_.counters().rejected_future, 1);
}

class FailsafeActionTest : public ::testing::Test {
 protected:
  ControlLoop make(const std::string& action) {
    config::Config c = config::load_config_file(
        source_path("config/team_quad.yaml"),
        {"inputs.failsafe=" + action, "inputs.hold_last_ms=200", "output.spool_up_s=0"});
    return ControlLoop(c, config::build_mixer(c));
  }
  static void arm(ControlLoop& loop) {
    loop.on_setpoint(SetpointSample{1, 0.0, 0, false}, 0, kWall);
    loop.on_pid(PidSample{1, 0.2, 0, 0}, 0, kWall);
    loop.cycle(0);
    loop.on_setpoint(SetpointSample{2, 0.05, 0, true}, 0, kWall);
    ASSERT_EQ(loop.cycle(0).state, LoopState::kArmed);
  }
};

TEST_F(FailsafeActionTest, HoldLastKeepsMixingForABoundedTime) {
  ControlLoop loop = make("hold_last");
  arm(loop);
  const double armed_output = loop.last().mix.output[0];
  const auto& r = loop.cycle(150 * kMs);  // stale, within the hold
  EXPECT_EQ(r.state, LoopState::kFailsafe);
  EXPECT_TRUE(r.mix.armed);
  EXPECT_EQ(r.mix.output[0], armed_output);
  EXPECT_FALSE(loop.cycle(351 * kMs).mix.armed);  // hold (200 ms) over: disarmed
}

TEST_F(FailsafeActionTest, IdleSpinsWithZeroDemand) {
  ControlLoop loop = make("idle");
  arm(loop);
  const auto& r = loop.cycle(150 * kMs);
  EXPECT_EQ(r.state, LoopState::kFailsafe);
  EXPECT_TRUE(r.mix.armed);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(r.mix.output[i], 1150.0);
}

// A status reports what is true in its own cycle: once disarmed, nothing
// saturated, nothing limited, nothing unallocated, even right after a
// saturated armed cycle (it used to repeat the last armed cycle's).
TEST(ControlLoopStatus, ADisarmedStatusReportsNoSaturation) {
  // quad X with `prioritized`: full throttle with full roll and pitch
  // saturates (the team quad's budgets never do).
  const config::Config config = config::load_config_file(
      source_path("config/quad_x.yaml"), {"inputs.arm_max_throttle=1", "output.spool_up_s=0"});
  ControlLoop loop_(config, config::build_mixer(config));
  std::int64_t utime = 1'700'000'000'000'000;
  const auto send = [&](std::int64_t now, bool armed, double throttle, double tilt) {
    ASSERT_EQ(loop_.on_setpoint(SetpointSample{utime += 1000, throttle, 0.0, armed}, now, kWall),
              Rejection::kNone);
    ASSERT_EQ(loop_.on_pid(PidSample{utime += 1000, tilt, tilt, 0.0}, now, kWall),
              Rejection::kNone);
  };
  send(0, false, 0.0, 0.0);
  loop_.cycle(0);
  send(1 * kMs, true, 1.0, 1.0);
  const auto status_of = [&](const loop::CycleResult& r) {
    mixer_status_t s;
    messages::fill_status_message(s, r, loop_.counters(), messages::LoopTiming{}, 0, 4, 0);
    return s;
  };
  const mixer_status_t armed = status_of(loop_.cycle(1 * kMs));
  ASSERT_EQ(armed.state, mixer_status_t::STATE_ARMED);
  ASSERT_NE(armed.saturated_upper | armed.saturated_lower, 0);
  bool any_limited = false;
  for (int a = 0; a < 4; ++a) any_limited = any_limited || armed.axis_limited[a];
  ASSERT_TRUE(any_limited);

  send(2 * kMs, false, 0.0, 0.0);
  const mixer_status_t disarmed = status_of(loop_.cycle(2 * kMs));
  ASSERT_EQ(disarmed.state, mixer_status_t::STATE_DISARMED);
  EXPECT_EQ(disarmed.saturated_upper, 0);
  EXPECT_EQ(disarmed.saturated_lower, 0);
  for (int a = 0; a < 4; ++a) {
    EXPECT_FALSE(disarmed.axis_limited[a]) << "axis " << a;
    EXPECT_EQ(disarmed.unallocated[a], 0.0F) << "axis " << a;
  }
  EXPECT_FALSE(disarmed.spooling_up);
  EXPECT_EQ(disarmed.spool_up, 0.0F);
  EXPECT_EQ(disarmed.motor_test_state, mixer_status_t::MOTOR_TEST_NONE);
  EXPECT_EQ(disarmed.failed_motors, 0);
  EXPECT_EQ(disarmed.thrust_gain, 1.0F);
}

}  // namespace
}  // namespace motormix::test
