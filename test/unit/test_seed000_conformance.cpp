// The team quad mixer against its document: the worked example, hand-derived
// truth-table rows, and a seeded sweep against a naive transcription.

#include "seed000_reference.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <random>

namespace motormix::test {
namespace {

struct Row {
  const char* what;
  Seed000Input in;
  std::array<double, 4> power;  // FL, FR, RL, RR, worked by hand from the document
};

class Seed000 : public ::testing::Test {
 protected:
  config::Config config_ = team_quad_config();
  Mixer mixer_ = config::build_mixer(config_);

  MixerOutput mix(const Seed000Input& in) {
    AxisVector demand;
    demand << in.roll, in.pitch, in.yaw, in.throttle;
    MixerOutput out;
    EXPECT_EQ(mixer_.mix(demand, out), MixStatus::kOk);
    return out;
  }
};

TEST_F(Seed000, ConfigIsTheTeamQuad) {
  EXPECT_EQ(config_.motors(), 4);
  EXPECT_EQ(config_.motor_names(), (std::vector<std::string>{"FL", "FR", "RL", "RR"}));
  EXPECT_EQ(config_.channels.setpoint, "pos_deseada");
  EXPECT_EQ(config_.channels.pid, "pid");
  EXPECT_EQ(config_.inputs.yaw_source, config::YawSource::kSetpoint);
  EXPECT_EQ(mixer_.allocator().name(), "legacy_budget");
}

// "Throttle 0, Roll 0.5: power 0.5 to the front and rear left motors, -0.5 to
// the right ones, which is ignored." Raw contributions 0.5 / 0; after the 25 %
// roll+pitch budget the left motors get 0.125 of full power.
TEST_F(Seed000, WorkedExampleRollHalf) {
  const MixerOutput out = mix({0.0, 0.5, 0.0, 0.0});
  EXPECT_NEAR(out.command[0], 0.5 * 0.25, kExact);
  EXPECT_NEAR(out.command[1], 0.0, kExact);
  EXPECT_NEAR(out.command[2], 0.5 * 0.25, kExact);
  EXPECT_NEAR(out.command[3], 0.0, kExact);
  EXPECT_NEAR(out.output[0], 1246.75, kExact);
  EXPECT_NEAR(out.output[1], 1150.0, kExact);
  EXPECT_NEAR(out.output[2], 1246.75, kExact);
  EXPECT_NEAR(out.output[3], 1150.0, kExact);
}

TEST_F(Seed000, TruthTable) {
  const std::vector<Row> rows = {
      {"idle", {0, 0, 0, 0}, {0, 0, 0, 0}},
      {"full throttle is 60 %", {1, 0, 0, 0}, {0.6, 0.6, 0.6, 0.6}},
      {"positive pitch: rear motors", {0, 0, 1, 0}, {0, 0, 0.25, 0.25}},
      {"negative pitch: front motors", {0, 0, -1, 0}, {0.25, 0.25, 0, 0}},
      {"positive yaw: FL and RR", {0, 0, 0, 1}, {0.15, 0, 0, 0.15}},
      {"negative yaw: FR and RL", {0, 0, 0, -1}, {0, 0.15, 0.15, 0}},
      {"negative roll: right motors", {0.5, -1, 0, 0}, {0.3, 0.55, 0.3, 0.55}},
      // RL: roll 0.25 + pitch 0.25 > 0.25, so each becomes 0.125.
      {"everything at full", {1, 1, 1, 1}, {1.0, 0.6, 0.85, 1.0}},
      {"roll and pitch share the budget", {0.5, 0.6, 0.6, 0}, {0.45, 0.3, 0.55, 0.45}},
      // RL: 0.25 + 0.025 > 0.25: the rule halves the budget between both, as written.
      {"the cap splits evenly, as written", {0, 1, 0.1, 0}, {0.25, 0, 0.25, 0.025}},
      {"exactly at the cap is left alone", {0, 0.5, 0.5, 0}, {0.125, 0, 0.25, 0.125}},
  };
  for (const Row& row : rows) {
    SCOPED_TRACE(row.what);
    const MixerOutput out = mix(row.in);
    for (int i = 0; i < 4; ++i) {
      EXPECT_NEAR(out.command[i], row.power[static_cast<std::size_t>(i)], kExact) << "motor " << i;
      EXPECT_NEAR(out.output[i], seed000_pwm(row.power[static_cast<std::size_t>(i)]), kExact);
    }
  }
}

TEST_F(Seed000, RandomInputsMatchTheDocument) {
  std::mt19937_64 rng(20261123);
  std::uniform_real_distribution<double> sym(-1.0, 1.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int k = 0; k < 200000; ++k) {
    const Seed000Input in{unit(rng), sym(rng), sym(rng), sym(rng)};
    const auto power = seed000_power(in);
    const MixerOutput out = mix(in);
    for (int i = 0; i < 4; ++i) {
      ASSERT_NEAR(out.command[i], power[static_cast<std::size_t>(i)], kExact);
      ASSERT_NEAR(out.output[i], seed000_pwm(power[static_cast<std::size_t>(i)]), kExact);
      ASSERT_GE(out.output[i], 1150.0);
      ASSERT_LE(out.output[i], 1924.0);
    }
  }
}

}  // namespace
}  // namespace motormix::test
