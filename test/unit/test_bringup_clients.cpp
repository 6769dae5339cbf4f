// The bring-up clients' sequences with time passed in: the ESC calibration
// (nothing sent while a mixer may drive the outputs, always ending at the
// disarmed values) and the motor-test client (one request at a time, its
// own answer only, a stop when interrupted).

#include "bringup/esc_calibration.hpp"
#include "bringup/motor_test_client.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

namespace motormix::test {
namespace {

using bringup::EscCalibration;
using Phase = EscCalibration::Phase;
using Outcome = EscCalibration::Outcome;

class EscCalibrationTest : public ::testing::Test {
 protected:
  config::Config config_ = config::load_config_file(source_path("config/quad_x.yaml"));
  bringup::EscCalibrationTiming timing_{1.0, 10.0, 2.0};
  EscCalibration cal_{config_, timing_, 0.0};
  double t_ = 0.0;
  // Steps every 10 ms up to `until`, returning the outputs published.
  std::vector<EscCalibration::Output> run_until(double until) {
    std::vector<EscCalibration::Output> published;
    for (; t_ <= until + 1e-9; t_ += 0.01) {
      const auto o = cal_.step(t_);
      if (o.publish) published.push_back(o);
    }
    return published;
  }
};

TEST_F(EscCalibrationTest, MaximumThenMinimumThenDisarmedAndDone) {
  EXPECT_TRUE(run_until(0.95).empty()) << "nothing while listening";
  auto out = run_until(3.0);
  ASSERT_FALSE(out.empty());
  for (const auto& o : out) {
    EXPECT_TRUE(o.armed);
    EXPECT_EQ((*o.pwm)[0], 2000.0);
    EXPECT_EQ(o.command, 1.0);
  }
  cal_.on_enter();
  out = run_until(5.0);
  for (const auto& o : out) {
    EXPECT_EQ((*o.pwm)[0], 1000.0);
    EXPECT_TRUE(o.armed);
  }
  out = run_until(6.0);
  ASSERT_FALSE(out.empty());
  EXPECT_EQ((*out.back().pwm)[0], 900.0);
  EXPECT_FALSE(out.back().armed);
  EXPECT_EQ(cal_.outcome(), Outcome::kCalibrated);
  EXPECT_TRUE(run_until(7.0).empty()) << "nothing once done";
}

TEST_F(EscCalibrationTest, AMixerHeardWhileListeningRefusesAndNothingIsSent) {
  run_until(0.5);
  cal_.on_mixer_heard();
  EXPECT_TRUE(run_until(20.0).empty());
  EXPECT_EQ(cal_.outcome(), Outcome::kRefused);
  EXPECT_NE(cal_.reason().find("mixer"), std::string::npos);
}

// Every way out of the maximum or the minimum goes to the disarmed values,
// never to the minimum without the user's Enter.
TEST_F(EscCalibrationTest, EveryAbortEndsDisarmed) {
  for (int way = 0; way < 5; ++way) {
    SCOPED_TRACE(way);
    EscCalibration cal(config_, timing_, 0.0);
    std::vector<EscCalibration::Output> out;
    for (double t = 0.0; t < 30.0 && cal.outcome() == Outcome::kRunning; t += 0.01) {
      if (t > 2.0) {
        if (way == 0) cal.on_interrupt();
        if (way == 1) cal.on_end_of_input();
        if (way == 2) cal.on_mixer_heard();
        // way 3: the timeout (10 s)
        if (way == 4 && t < 2.05) cal.on_enter();
        if (way == 4 && t > 2.5) cal.on_interrupt();  // during the minimum
      }
      const auto o = cal.step(t);
      if (o.publish) out.push_back(o);
    }
    EXPECT_EQ(cal.outcome(), Outcome::kAborted);
    EXPECT_FALSE(cal.reason().empty());
    ASSERT_FALSE(out.empty());
    EXPECT_EQ((*out.back().pwm)[0], 900.0);
    EXPECT_FALSE(out.back().armed);
    if (way != 4) {
      for (const auto& o : out) EXPECT_NE((*o.pwm)[0], 1000.0) << "no minimum without Enter";
    }
  }
}

TEST(EscCalibrationRefusal, OnlyUnipolarOutputsCanBeCalibrated) {
  EXPECT_EQ(
      bringup::calibration_refusal(config::load_config_file(source_path("config/quad_x.yaml"))),
      "");
  EXPECT_NE(
      bringup::calibration_refusal(config::load_config_file(source_path("config/diff_drive.yaml"))),
      "");
}

using bringup::MotorTestAnswer;
using bringup::MotorTestClient;
using Kind = MotorTestClient::Action::Kind;

TEST(MotorTestClient, ASequenceAsksWaitsForItsOwnAnswerAndForTheEnd) {
  MotorTestClient client({0, 2}, 0.1, 2.0, 3.0);
  auto a = client.step(0.0, 100, nullptr);
  ASSERT_EQ(a.kind, Kind::kSend);
  EXPECT_EQ(a.motor, 1);
  EXPECT_EQ(a.utime, 100);
  // An older answer (another request) is not ours.
  MotorTestAnswer old{50, loop::MotorTestResult::kRefusedThrottle, false};
  EXPECT_EQ(client.step(0.1, 101, &old).kind, Kind::kWait);
  MotorTestAnswer ours{100, loop::MotorTestResult::kOk, true};
  a = client.step(0.2, 102, &ours);
  EXPECT_EQ(a.kind, Kind::kSpinning);
  EXPECT_EQ(a.motor, 1);
  EXPECT_EQ(client.step(1.0, 103, &ours).kind, Kind::kWait);
  ours.running = false;
  EXPECT_EQ(client.step(2.2, 104, &ours).kind, Kind::kWait);  // ended: a pause before the next
  EXPECT_EQ(client.step(3.0, 105, &ours).kind, Kind::kWait);
  EXPECT_EQ(client.step(3.3, 106, &ours).kind, Kind::kWait);  // the pause ends here
  a = client.step(3.31, 107, &ours);
  ASSERT_EQ(a.kind, Kind::kSend);
  EXPECT_EQ(a.motor, 3);
  MotorTestAnswer second{107, loop::MotorTestResult::kOk, true};
  EXPECT_EQ(client.step(3.4, 108, &second).kind, Kind::kSpinning);
  // The mixer never says it ended: the client goes on after duration + grace.
  EXPECT_EQ(client.step(6.0, 109, &second).kind, Kind::kWait);
  EXPECT_EQ(client.step(6.5, 110, &second).kind, Kind::kWait);
  EXPECT_EQ(client.step(6.6, 111, &second).kind, Kind::kDone);
  EXPECT_TRUE(client.finished());
}

TEST(MotorTestClient, SilenceRefusalAndInterruptEndIt) {
  MotorTestClient silent({0}, 0.1, 2.0, 3.0);
  silent.step(0.0, 100, nullptr);
  EXPECT_EQ(silent.step(2.9, 101, nullptr).kind, Kind::kWait);
  EXPECT_EQ(silent.step(3.0, 102, nullptr).kind, Kind::kNoAnswer);

  MotorTestClient refused({0}, 0.1, 2.0, 3.0);
  refused.step(0.0, 100, nullptr);
  const MotorTestAnswer no{100, loop::MotorTestResult::kRefusedNotDisarmed, false};
  const auto a = refused.step(0.1, 101, &no);
  EXPECT_EQ(a.kind, Kind::kRefused);
  EXPECT_EQ(a.refusal, loop::MotorTestResult::kRefusedNotDisarmed);

  MotorTestClient stopped({0, 1}, 0.1, 2.0, 3.0);
  stopped.step(0.0, 100, nullptr);
  stopped.on_interrupt();
  EXPECT_EQ(stopped.step(0.1, 101, nullptr).kind, Kind::kStopped);
  EXPECT_EQ(stopped.step(0.2, 102, nullptr).kind, Kind::kDone);
}

}  // namespace
}  // namespace motormix::test
