// The new inputs end to end through the control loop, with injected time:
// motor_status (failure sets in flight), battery voltage (thrust
// compensation), their decoders against hostile bytes, and their config keys.

#include "loop/control_loop.hpp"
#include "messages/input_reader.hpp"
#include "messages/messages.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace motormix::test {
namespace {

using loop::BatterySample;
using loop::ControlLoop;
using loop::LoopState;
using loop::MotorStatusSample;
using loop::PidSample;
using loop::Rejection;
using loop::SetpointSample;

// The compensated gain and command after the loop's float and double steps.
constexpr double kCompensatedGain = 1e-9;

class FailureInputsTest : public ::testing::Test {
 protected:
  void make(const std::vector<std::string>& overrides) {
    std::vector<std::string> all = {"inputs.arm_max_throttle=1", "output.spool_up_s=0"};
    all.insert(all.end(), overrides.begin(), overrides.end());
    config_ = config::load_config_file(source_path("config/hexa_x.yaml"), all);
    loop_.emplace(config_, config::build_mixer(config_));
  }
  void inputs(std::int64_t now, bool armed, double throttle = 0.5) {
    utime_ += 1000;
    ASSERT_EQ(loop_->on_setpoint(SetpointSample{utime_, throttle, 0.0, armed}, now, kWall),
              Rejection::kNone);
    ASSERT_EQ(loop_->on_pid(PidSample{utime_, 0.0, 0.0, 0.0}, now, kWall), Rejection::kNone);
  }
  void arm(std::int64_t now) {
    inputs(now, false);
    loop_->cycle(now);
    inputs(now, true);
    ASSERT_EQ(loop_->cycle(now).state, LoopState::kArmed);
  }
  Rejection status(std::int64_t now, std::uint32_t failed, int n = 6) {
    return loop_->on_motor_status(MotorStatusSample{utime_ += 1000, n, failed}, now, kWall);
  }

  config::Config config_;
  std::optional<ControlLoop> loop_;
  std::int64_t utime_ = 1'700'000'000'000'000;
};

TEST_F(FailureInputsTest, MotorStatusSwitchesTheFailureSetInFlight) {
  make({"mixer.strategy=optimal"});
  arm(0);
  EXPECT_EQ(loop_->last().failed, 0U);
  ASSERT_EQ(status(1 * kMs, 0b000100), Rejection::kNone);
  inputs(2 * kMs, true);
  const loop::CycleResult& r = loop_->cycle(2 * kMs);
  EXPECT_EQ(r.state, LoopState::kArmed) << "a failure does not disarm";
  EXPECT_EQ(r.failed, 0b000100U);
  EXPECT_EQ(r.failure, FailureHandling::kReallocated);
  EXPECT_EQ(r.mix.output[2], config_.outputs[2].disarmed);
  // A later message clears it.
  ASSERT_EQ(status(3 * kMs, 0), Rejection::kNone);
  inputs(4 * kMs, true);
  EXPECT_EQ(loop_->cycle(4 * kMs).failed, 0U);
  EXPECT_EQ(loop_->counters().motor_status_received, 2);
}

TEST_F(FailureInputsTest, ConfiguredFailuresStayWhateverMotorStatusSays) {
  make({"mixer.failed_motors=[m2]"});
  arm(0);
  EXPECT_EQ(loop_->last().failed, 0b10U);
  ASSERT_EQ(status(1 * kMs, 0b100000), Rejection::kNone);
  inputs(2 * kMs, true);
  EXPECT_EQ(loop_->cycle(2 * kMs).failed, 0b100010U);
  ASSERT_EQ(status(3 * kMs, 0), Rejection::kNone);
  inputs(4 * kMs, true);
  EXPECT_EQ(loop_->cycle(4 * kMs).failed, 0b10U);
}

TEST_F(FailureInputsTest, BadMotorStatusIsRejectedAndCounted) {
  make({});
  arm(0);
  EXPECT_EQ(status(1 * kMs, 0b1, 4), Rejection::kWrongSize);
  EXPECT_EQ(loop_->counters().rejected_size, 1);
  ASSERT_EQ(status(2 * kMs, 0b1), Rejection::kNone);
  // Older than the last accepted one: out of order.
  EXPECT_EQ(loop_->on_motor_status(MotorStatusSample{utime_ - 500, 6, 0}, 3 * kMs, kWall),
            Rejection::kOutOfOrder);
  EXPECT_EQ(loop_->on_motor_status(MotorStatusSample{kWall + 10'000'000, 6, 0}, 3 * kMs, kWall),
            Rejection::kFromFuture);
  inputs(4 * kMs, true);
  EXPECT_EQ(loop_->cycle(4 * kMs).failed, 0b1U) << "the rejected messages changed nothing";
  EXPECT_EQ(loop_->counters().rejected_out_of_order, 1);
  EXPECT_EQ(loop_->counters().rejected_future, 1);
}

TEST_F(FailureInputsTest, BatteryScalesTheThrustDemandWhileFresh) {
  make({"battery={nominal_v: 16.8, filter_hz: 2, timeout_ms: 500}", "mixer.strategy=clip"});
  arm(0);
  const double healthy = loop_->last().mix.command[0];  // 0.5 at hover
  ASSERT_EQ(loop_->on_battery(BatterySample{utime_ += 1000, 14.0}, 1 * kMs, kWall),
            Rejection::kNone);
  inputs(2 * kMs, true);
  const loop::CycleResult& r = loop_->cycle(2 * kMs);
  EXPECT_EQ(r.battery, BatteryState::kOk);
  EXPECT_NEAR(r.thrust_gain, 16.8 / 14.0, kCompensatedGain);
  EXPECT_NEAR(r.mix.command[0], healthy * 16.8 / 14.0, kCompensatedGain);
  // Stale: back to no compensation, and the status says why (the loop keeps
  // cycling with fresh setpoints and pid meanwhile).
  for (std::int64_t t = 50; t < 600; t += 50) {
    inputs(t * kMs, true);
    ASSERT_EQ(loop_->cycle(t * kMs).state, LoopState::kArmed);
  }
  inputs(600 * kMs, true);
  const loop::CycleResult& stale = loop_->cycle(600 * kMs);
  EXPECT_EQ(stale.battery, BatteryState::kStale);
  EXPECT_EQ(stale.thrust_gain, 1.0);
  EXPECT_NEAR(stale.mix.command[0], healthy, kCompensatedGain);
  // Implausible and non-finite readings are counted and not used.
  EXPECT_EQ(loop_->on_battery(BatterySample{utime_ += 1000, 2.0}, 601 * kMs, kWall),
            Rejection::kOutOfRange);
  EXPECT_EQ(loop_->on_battery(BatterySample{utime_ += 1000, NAN}, 602 * kMs, kWall),
            Rejection::kNonFinite);
  inputs(603 * kMs, true);
  EXPECT_EQ(loop_->cycle(603 * kMs).battery, BatteryState::kImplausible);
  EXPECT_EQ(loop_->last().thrust_gain, 1.0);
  EXPECT_EQ(loop_->counters().rejected_range, 1);
  EXPECT_EQ(loop_->counters().rejected_nonfinite, 1);
  EXPECT_EQ(loop_->counters().battery_received, 1);
}

TEST_F(FailureInputsTest, WithoutABatterySectionVoltagesAreIgnored) {
  make({});
  arm(0);
  EXPECT_EQ(loop_->on_battery(BatterySample{utime_ += 1000, 10.0}, 1 * kMs, kWall),
            Rejection::kNone);
  inputs(2 * kMs, true);
  EXPECT_EQ(loop_->cycle(2 * kMs).battery, BatteryState::kOff);
  EXPECT_EQ(loop_->last().thrust_gain, 1.0);
  EXPECT_EQ(loop_->counters().battery_received, 0);
}

TEST_F(FailureInputsTest, InputAgesAreReported) {
  make({});
  EXPECT_EQ(loop_->cycle(0).input_age_ms[3], -1.0);
  inputs(10 * kMs, false);
  status(10 * kMs, 0);
  const loop::CycleResult& r = loop_->cycle(25 * kMs);
  EXPECT_DOUBLE_EQ(r.input_age_ms[0], 15.0);
  EXPECT_DOUBLE_EQ(r.input_age_ms[1], 15.0);
  EXPECT_DOUBLE_EQ(r.input_age_ms[2], -1.0);
  EXPECT_DOUBLE_EQ(r.input_age_ms[3], 15.0);
}

std::vector<std::uint8_t> encode_status(int n, std::vector<std::int8_t> failed) {
  motor_status_t m{};
  m.utime = 5;
  m.num_motors = n;
  m.failed = std::move(failed);
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(buf.data(), 0, static_cast<int>(buf.size()));
  return buf;
}

// Reads bytes as an input of `kind` the node's way (bus::receive, no
// signing); the sample in `out` when taken.
template <typename Sample>
bus::Refusal read_input(messages::InputKind kind, const std::uint8_t* data, std::size_t size,
                        Sample& out) {
  signing::Policy policy;
  messages::InputReader reader;
  messages::InputSample in;
  const bus::Refusal r = reader.read(kind, policy, "INPUT", data, size, 0, in);
  if (r == bus::Refusal::kNone) out = std::get<Sample>(in);
  return r;
}

TEST(MotorStatusDecoder, AcceptsWholeMessagesOnly) {
  constexpr auto kStatus = messages::InputKind::kMotorStatus;
  MotorStatusSample s;
  std::vector<std::uint8_t> ok = encode_status(6, {0, 0, 1, 0, 0, 1});
  ASSERT_EQ(read_input(kStatus, ok.data(), ok.size(), s), bus::Refusal::kNone);
  EXPECT_EQ(s.num_motors, 6);
  EXPECT_EQ(s.failed, 0b100100U);
  EXPECT_EQ(read_input(kStatus, ok.data(), ok.size() - 1, s), bus::Refusal::kTruncated);
  ok.push_back(0);
  EXPECT_EQ(read_input(kStatus, ok.data(), ok.size(), s), bus::Refusal::kTrailing);
  EXPECT_EQ(read_input(kStatus, ok.data(), 3, s), bus::Refusal::kTruncated);
  EXPECT_EQ(read_input(kStatus, nullptr, 0, s), bus::Refusal::kTruncated);
}

TEST(MotorStatusDecoder, HostileLengthIsRefusedBeforeDecoding) {
  // num_motors = 2^31 - 1 in a 21-byte message: the generated decoder would
  // size its array first; ours refuses it from the header.
  constexpr auto kStatus = messages::InputKind::kMotorStatus;
  std::vector<std::uint8_t> bad = encode_status(1, {1});
  bad[16] = 0x7f;
  bad[17] = bad[18] = bad[19] = 0xff;
  MotorStatusSample s;
  EXPECT_EQ(read_input(kStatus, bad.data(), bad.size(), s), bus::Refusal::kBadLength);
  bad[16] = 0x80;  // negative
  bad[17] = bad[18] = bad[19] = 0x00;
  EXPECT_EQ(read_input(kStatus, bad.data(), bad.size(), s), bus::Refusal::kBadLength);
  // 17 motors: more than any mixer has.
  std::vector<std::uint8_t> big = encode_status(17, std::vector<std::int8_t>(17, 0));
  EXPECT_EQ(read_input(kStatus, big.data(), big.size(), s), bus::Refusal::kBadLength);
}

TEST(BatteryDecoder, WrongTypeIsRefused) {
  battery_t b{};
  b.utime = 7;
  b.voltage = 15.5F;
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(b.getEncodedSize()));
  b.encode(buf.data(), 0, static_cast<int>(buf.size()));
  BatterySample s;
  ASSERT_EQ(read_input(messages::InputKind::kBattery, buf.data(), buf.size(), s),
            bus::Refusal::kNone);
  EXPECT_EQ(s.voltage, 15.5);
  const std::vector<std::uint8_t> status = encode_status(6, std::vector<std::int8_t>(6, 0));
  EXPECT_EQ(read_input(messages::InputKind::kBattery, status.data(), status.size(), s),
            bus::Refusal::kWrongType);
}

void expect_config_error(const std::string& yaml, const std::string& needle) {
  try {
    config::load_config_text(yaml, "test.yaml");
    ADD_FAILURE() << "accepted: " << yaml;
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(FailureConfig, MotorsByNumberOrName) {
  const config::Config c = config::load_config_text(
      "geometry: {preset: hexa_x}\nmixer: {failed_motors: [3, m5]}\n", "test.yaml");
  EXPECT_EQ(c.failed_motors, 0b10100U);
  expect_config_error("geometry: {preset: hexa_x}\nmixer: {failed_motors: [7]}\n",
                      "'mixer.failed_motors[0]': found '7'");
  expect_config_error("geometry: {preset: hexa_x}\nmixer: {failed_motors: [0]}\n",
                      "motor numbers 1..6");
  expect_config_error("geometry: {preset: hexa_x}\nmixer: {failed_motors: [m9]}\n", "m9");
  expect_config_error("geometry: {preset: hexa_x}\nmixer: {failed_motors: [2, m2]}\n",
                      "listed twice");
  expect_config_error("geometry: {preset: quad_x}\nmixer: {failed_motors: [1, 2, 3, 4]}\n",
                      "at least one working motor");
  expect_config_error("geometry: {preset: hexa_x}\nmixer: {failed_motors: 3}\n",
                      "'mixer.failed_motors'");
  expect_config_error(
      "geometry: {preset: quad_x}\nmixer: {strategy: legacy_budget, failed_motors: [1]}\n",
      "no reallocation");
}

TEST(BatteryConfig, ValidatedWithKeyValueAndRange) {
  const config::Config c = config::load_config_text(
      "geometry: {preset: quad_x}\nbattery: {nominal_v: 16.8, exponent: 1.2, max_gain: 1.4, "
      "filter_hz: 3, timeout_ms: 250}\n",
      "test.yaml");
  ASSERT_TRUE(c.battery);
  EXPECT_EQ(c.battery->exponent, 1.2);
  EXPECT_EQ(c.battery->timeout_s, 0.25);
  EXPECT_EQ(c.battery->min_v, 8.4);
  EXPECT_EQ(c.channels.battery, "BATTERY");
  EXPECT_EQ(c.channels.motor_status, "MOTOR_STATUS");
  EXPECT_FALSE(config::load_config_text("geometry: {preset: quad_x}\n", "t.yaml").battery);
  expect_config_error("geometry: {preset: quad_x}\nbattery: {exponent: 1}\n",
                      "'battery.nominal_v': found nothing");
  expect_config_error("geometry: {preset: quad_x}\nbattery: {nominal_v: 16.8, max_gain: 0.5}\n",
                      "'battery.max_gain': found '0.5'");
  expect_config_error("geometry: {preset: quad_x}\nbattery: {nominal_v: 16.8, filter_hz: 1000}\n",
                      "'battery.filter_hz'");
  expect_config_error("geometry: {preset: quad_x}\nbattery: {nominal_v: 16.8, min_v: 17}\n",
                      "min_v < nominal_v");
  expect_config_error("geometry: {preset: quad_x}\nbattery: {nominal_v: 16.8, voltage: 3}\n",
                      "battery.voltage");
}

}  // namespace
}  // namespace motormix::test
