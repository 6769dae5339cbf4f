// The embedding API: what a program that links motormix::config sees.

#include "test_support.hpp"

#include <motormix/embedded_mixer.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <regex>
#include <sstream>

namespace motormix::test {
namespace {

TEST(EmbeddedMixer, SeedWorkedExample) {
  auto mixer = EmbeddedMixer::from_file(source_path("config/team_quad.yaml"));
  ASSERT_EQ(mixer.motors(), 4);
  EXPECT_EQ(mixer.motor_names()[0], "FL");
  Demand d;
  d.roll = 0.5;
  const MixReport r = mixer.mix(d);
  EXPECT_EQ(r.status, MixStatus::kOk);
  EXPECT_TRUE(r.armed);
  EXPECT_NEAR(r.pwm[0], 1246.75, kExact);  // left motors 0.125 of the range
  EXPECT_NEAR(r.pwm[1], 1150.0, kExact);
  EXPECT_NEAR(r.command[2], 0.125, kExact);
  EXPECT_TRUE(r.saturated(1));
  EXPECT_FALSE(r.saturated(0));
}

TEST(EmbeddedMixer, ReportsSaturationAndNeverLeavesTheRange) {
  auto mixer = EmbeddedMixer::from_file(source_path("config/quad_x.yaml"));
  Demand d;
  d.thrust = 0.6;
  d.roll = 0.3;
  d.yaw = 0.8;
  const MixReport r = mixer.mix(d);
  EXPECT_FALSE(r.delivered(Axis::kYaw));
  EXPECT_TRUE(r.delivered(Axis::kRoll));
  EXPECT_GT(std::abs(r.unallocated[index(Axis::kYaw)]), 0.1);
  for (int i = 0; i < mixer.motors(); ++i) {
    EXPECT_GE(r.pwm[i], 1000.0);
    EXPECT_LE(r.pwm[i], 2000.0);
  }
  d.roll = std::numeric_limits<double>::quiet_NaN();
  const MixReport bad = mixer.mix(d);
  EXPECT_EQ(bad.status, MixStatus::kNonFiniteDemand);
  EXPECT_FALSE(bad.armed);
  for (int i = 0; i < mixer.motors(); ++i) EXPECT_EQ(bad.pwm[i], 900.0);  // disarmed value
  d.roll = 7.0;
  EXPECT_EQ(mixer.mix(d).status, MixStatus::kDemandClamped);
  const MixReport off = mixer.disarm();
  EXPECT_FALSE(off.armed);
  EXPECT_EQ(off.pwm[0], 900.0);
}

TEST(EmbeddedMixer, ConfigurationErrorsNameTheKey) {
  try {
    EmbeddedMixer::from_yaml("geometry: {preset: quad_x}\nloop_rate_hz: 3\n");
    FAIL() << "accepted loop_rate_hz 3";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("loop_rate_hz"), std::string::npos) << e.what();
  }
  EXPECT_THROW(EmbeddedMixer::from_file("/nonexistent/mixer.yaml"), config::ConfigError);
  EXPECT_THROW(EmbeddedMixer::from_yaml("geometry: {preset: quad_x}", {"output.min=5000"}),
               config::ConfigError);
}

// The guide (docs/embedding.md) shows examples/embedding/embed.cpp; the
// package test compiles and runs that file against the installed tree.
// Here: the guide's copy is that file, line for line.
TEST(EmbeddedMixer, GuideShowsTheExampleThatIsBuilt) {
  std::ifstream readme_file(source_path("docs/embedding.md"));
  std::ifstream example_file(source_path("examples/embedding/embed.cpp"));
  std::stringstream readme, example;
  readme << readme_file.rdbuf();
  example << example_file.rdbuf();
  ASSERT_FALSE(example.str().empty());
  EXPECT_NE(readme.str().find("```cpp\n" + example.str() + "```"), std::string::npos)
      << "docs/embedding.md must contain examples/embedding/embed.cpp verbatim in a ```cpp block";
  int lines = 0;
  for (char c : example.str()) lines += c == '\n';
  EXPECT_LE(lines, 25) << "the embedding example should stay short";
}

}  // namespace
}  // namespace motormix::test

namespace motormix::test {
namespace {

TEST(EmbeddedMixer, FailedMotorsPerCallAndFromTheConfiguration) {
  EmbeddedMixer m =
      EmbeddedMixer::from_file(source_path("config/hexa_x.yaml"), {"mixer.failed_motors=[6]"});
  Demand hover;
  hover.thrust = 0.5;
  const MixReport r = m.mix(hover, 0.0, MotorMask{1});  // m1 now, m6 from the file
  EXPECT_EQ(r.failed, 0b100001U);
  EXPECT_EQ(r.command[0], 0.0);
  EXPECT_EQ(r.command[5], 0.0);
  EXPECT_EQ(r.pwm[0], m.config().outputs[0].disarmed);
  EXPECT_NE(r.failure, FailureHandling::kNone);
  EXPECT_EQ(m.mix(hover).failed, 0b100000U);
}

}  // namespace
}  // namespace motormix::test
