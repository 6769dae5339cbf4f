// The control loop's decisions with injected time: arming, staleness,
// failsafe, recovery and rejection accounting.

#include "node/control_loop.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <limits>

namespace motormix::test {
namespace {

using node::ControlLoop;
using node::FailsafeReason;
using node::LoopState;
using node::PidSample;
using node::Rejection;
using node::SetpointSample;

constexpr std::int64_t kMs = 1000;

class ControlLoopTest : public ::testing::Test {
 protected:
  config::Config config_ = team_quad_config();
  ControlLoop loop_{config_, config::build_mixer(config_)};
  std::int64_t utime_ = 1'700'000'000'000'000;

  void setpoint(std::int64_t now, bool armed, double throttle = 0.5, double yaw = 0.0) {
    ASSERT_EQ(loop_.on_setpoint(SetpointSample{utime_ += 1000, throttle, yaw, armed}, now),
              Rejection::kNone);
  }
  void pid(std::int64_t now, double roll = 0.0, double pitch = 0.0) {
    ASSERT_EQ(loop_.on_pid(PidSample{utime_ += 1000, roll, pitch, 0.0}, now), Rejection::kNone);
  }
  void arm(std::int64_t now) {
    setpoint(now, false);
    pid(now);
    ASSERT_EQ(loop_.cycle(now).state, LoopState::kDisarmed);
    setpoint(now, true);
    ASSERT_EQ(loop_.cycle(now).state, LoopState::kArmed);
  }
  static void expect_disarmed_outputs(const node::CycleResult& r) {
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
  setpoint(150 * kMs, true);
  const auto& r = loop_.cycle(150 * kMs);
  EXPECT_EQ(r.state, LoopState::kFailsafe);
  EXPECT_EQ(r.reason, FailsafeReason::kPidStale);
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
  EXPECT_EQ(loop_.on_pid(PidSample{utime_ + 1, nan, 0, 0}, 1 * kMs), Rejection::kNonFinite);
  EXPECT_EQ(loop_.on_pid(PidSample{utime_ + 2, 1.5, 0, 0}, 1 * kMs), Rejection::kOutOfRange);
  EXPECT_EQ(loop_.on_setpoint(SetpointSample{utime_ + 3, -0.1, 0, true}, 1 * kMs),
            Rejection::kOutOfRange);
  EXPECT_EQ(loop_.on_pid(PidSample{utime_ - 500'000, 0.2, 0, 0}, 1 * kMs), Rejection::kOutOfOrder);
  loop_.on_undecodable();
  const auto& c = loop_.counters();
  EXPECT_EQ(c.rejected_nonfinite, 1);
  EXPECT_EQ(c.rejected_range, 2);
  EXPECT_EQ(c.rejected_out_of_order, 1);
  EXPECT_EQ(c.rejected_decode, 1);
  const auto& r = loop_.cycle(1 * kMs);
  EXPECT_EQ(r.state, LoopState::kArmed);
  EXPECT_NEAR(r.mix.output[0], 1150.0 + 0.3 * 774.0, kExact);  // roll still 0
  // The good inputs age out as usual despite the rejected traffic.
  EXPECT_EQ(loop_.cycle(150 * kMs).state, LoopState::kFailsafe);
}

TEST_F(ControlLoopTest, PublisherRestartWithEarlierClockIsAccepted) {
  arm(0);
  EXPECT_EQ(loop_.on_pid(PidSample{1000, 0.1, 0, 0}, 1 * kMs), Rejection::kNone);
}

TEST_F(ControlLoopTest, YawFromPidWhenConfigured) {
  config_.inputs.yaw_source = config::YawSource::kPid;
  ControlLoop loop(config_, config::build_mixer(config_));
  loop.on_setpoint(SetpointSample{1, 0.0, 1.0, false}, 0);
  loop.on_pid(PidSample{1, 0.0, 0.0, -1.0}, 0);
  loop.cycle(0);
  loop.on_setpoint(SetpointSample{2, 0.0, 1.0, true}, 0);
  const auto& r = loop.cycle(0);
  ASSERT_EQ(r.state, LoopState::kArmed);
  // Negative yaw from the pid: FR and RL get 15 %.
  EXPECT_NEAR(r.mix.command[1], 0.15, kExact);
  EXPECT_NEAR(r.mix.command[0], 0.0, kExact);
}

}  // namespace
}  // namespace motormix::test
