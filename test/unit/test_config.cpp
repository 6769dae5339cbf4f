// The config loader: strict schema, errors that name key, value and range.

#include "test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace motormix::test {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

const char* const kMinimal = "geometry: {preset: team_quad}\n";

std::string error_of(const std::string& yaml, const std::vector<std::string>& overrides = {}) {
  try {
    config::load_config_text(yaml, "test.yaml", overrides);
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(Config, MinimalConfigGetsDocumentedDefaults) {
  const config::Config c = config::load_config_text(kMinimal, "test.yaml");
  EXPECT_EQ(c.motors(), 4);
  EXPECT_EQ(c.channels.setpoint, "SETPOINT");
  EXPECT_EQ(c.channels.pid, "PID");
  EXPECT_EQ(c.channels.motor_pwm, "MOTOR_PWM");
  EXPECT_EQ(c.channels.status, "MIXER_STATUS");
  EXPECT_EQ(c.loop_rate_hz, 400.0);
  EXPECT_EQ(c.inputs.setpoint_timeout_s, 0.1);
  EXPECT_EQ(c.outputs[0].disarmed, 1000.0);
}

TEST(Config, BundledTeamQuadLoads) {
  const config::Config c = team_quad_config();
  EXPECT_EQ(c.outputs[3].min, 1150.0);
  EXPECT_EQ(c.outputs[3].max, 1924.0);
  EXPECT_EQ(c.legacy_budgets.throttle, 0.60);
}

TEST(Config, UnknownKeysAreErrorsWithTheirPath) {
  EXPECT_THAT(error_of(std::string(kMinimal) + "mixer: {strategy: legacy_budget, gain: 2}\n"),
              AllOf(HasSubstr("'mixer.gain'"), HasSubstr("not known"), HasSubstr("line 2")));
  EXPECT_THAT(error_of(std::string(kMinimal) + "loop_rate: 400\n"), HasSubstr("'loop_rate'"));
}

TEST(Config, OutOfRangeNamesKeyValueAndRange) {
  EXPECT_THAT(
      error_of(std::string(kMinimal) + "mixer: {legacy_budget: {yaw: 1.5}}\n"),
      AllOf(HasSubstr("mixer.legacy_budget.yaw"), HasSubstr("'1.5'"), HasSubstr("from 0 to 1")));
  EXPECT_THAT(error_of(std::string(kMinimal) + "loop_rate_hz: 20\n"),
              AllOf(HasSubstr("loop_rate_hz"), HasSubstr("'20'"), HasSubstr("from 50 to 10000")));
  EXPECT_THAT(error_of(std::string(kMinimal) + "output: {min: 1500, max: 1200}\n"),
              AllOf(HasSubstr("output.max"), HasSubstr("greater than min")));
  EXPECT_THAT(error_of(std::string(kMinimal) + "inputs: {pid_timeout_ms: .nan}\n"),
              HasSubstr("inputs.pid_timeout_ms"));
}

TEST(Config, BudgetsMayNotExceedFullPower) {
  EXPECT_THAT(
      error_of(std::string(kMinimal) + "mixer: {legacy_budget: {throttle: 0.8, yaw: 0.2}}\n"),
      AllOf(HasSubstr("mixer.legacy_budget"), HasSubstr("= 1.25"), HasSubstr("at most 1")));
}

TEST(Config, WrongTypesAreErrors) {
  EXPECT_THAT(error_of(std::string(kMinimal) + "loop_rate_hz: fast\n"),
              AllOf(HasSubstr("loop_rate_hz"), HasSubstr("'fast'")));
  EXPECT_THAT(error_of(std::string(kMinimal) + "output: [1, 2]\n"),
              AllOf(HasSubstr("'output'"), HasSubstr("a mapping")));
  EXPECT_THAT(error_of(std::string(kMinimal) + "mixer: {strategy: magic}\n"),
              AllOf(HasSubstr("mixer.strategy"), HasSubstr("'magic'"), HasSubstr("one of")));
}

TEST(Config, GeometryIsRequiredAndExclusive) {
  EXPECT_THAT(error_of("name: x\n"), HasSubstr("'geometry'"));
  EXPECT_THAT(error_of("geometry: {preset: team_quad, mixing: [[1,1,1,1]]}\n"),
              AllOf(HasSubstr("found preset, mixing"), HasSubstr("exactly one of")));
  EXPECT_THAT(error_of("geometry: {preset: dodecacopter}\n"),
              AllOf(HasSubstr("geometry.preset"), HasSubstr("'dodecacopter'")));
}

TEST(Config, ExplicitMixingTable) {
  const config::Config c = config::load_config_text(
      "geometry:\n  mixing: [[1, -1, 1, 1], [-1, -1, -1, 1], [1, 1, -1, 1], [-1, 1, 1, 1]]\n"
      "  motor_names: [a, b, c, d]\n",
      "test.yaml");
  EXPECT_EQ(c.mixing, team_quad_config().mixing);
  EXPECT_EQ(c.motor_names()[2], "c");
  EXPECT_THAT(error_of("geometry: {mixing: [[1, 1, 1], [1, 1, 1, 1]]}\n"),
              AllOf(HasSubstr("geometry.mixing[0]"), HasSubstr("row of 4")));
  EXPECT_THAT(error_of("geometry: {mixing: [[1, 1, x, 1]]}\n"),
              AllOf(HasSubstr("geometry.mixing[0][2] (yaw)"), HasSubstr("'x'")));
  EXPECT_THAT(error_of("geometry: {mixing: [[1,1,1,1]], motor_names: [a, b]}\n"),
              HasSubstr("geometry.motor_names"));
}

TEST(Config, MalformedYamlAndMissingFile) {
  EXPECT_THAT(error_of("geometry: {preset: team_quad\n"), HasSubstr("not valid YAML"));
  EXPECT_THROW(config::load_config_file("/nonexistent/motormix.yaml"), config::ConfigError);
  EXPECT_THAT(error_of("[1, 2, 3]\n"), HasSubstr("a mapping"));
}

TEST(Config, OverridesApplyBeforeValidation) {
  const config::Config c =
      config::load_config_text(kMinimal, "test.yaml", {"loop_rate_hz=1000", "channels.pid=ATT"});
  EXPECT_EQ(c.loop_rate_hz, 1000.0);
  EXPECT_EQ(c.channels.pid, "ATT");
  EXPECT_THAT(error_of(kMinimal, {"loop_rate_hz=1"}), HasSubstr("loop_rate_hz"));
  EXPECT_THAT(error_of(kMinimal, {"no_equals_sign"}), HasSubstr("key.path=value"));
  EXPECT_THAT(error_of(kMinimal, {"channels.nope=X"}), HasSubstr("channels.nope"));
}

TEST(Config, EveryChannelHasOneUse) {
  EXPECT_THAT(
      error_of(kMinimal, {"channels.pid=SETPOINT"}),
      AllOf(HasSubstr("channels.pid"), HasSubstr("'SETPOINT'"), HasSubstr("channels.setpoint")));
  EXPECT_THAT(error_of(kMinimal, {"channels.status=PID"}),
              AllOf(HasSubstr("channels.status"), HasSubstr("channels.pid")));
  EXPECT_THAT(error_of(kMinimal, {"channels.battery=MOTOR_PWM"}),
              AllOf(HasSubstr("channels.battery"), HasSubstr("channels.motor_pwm")));
  EXPECT_EQ(error_of(kMinimal, {"channels.pid=ATT", "channels.setpoint=SP"}), "(accepted)");
}

TEST(Config, StatusRateNotAboveLoopRate) {
  EXPECT_THAT(error_of(std::string(kMinimal) + "loop_rate_hz: 100\nstatus_rate_hz: 200\n"),
              HasSubstr("status_rate_hz"));
}

}  // namespace
}  // namespace motormix::test
