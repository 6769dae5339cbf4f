// The core pipeline's promises: range, refusal of non-finite demand, clamping,
// and honest reporting of what was not delivered.

#include "test_support.hpp"

#include <motormix/effectiveness/mixing_matrix.hpp>

#include <gtest/gtest.h>

#include <limits>
#include <random>

namespace motormix::test {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

OutputChannel esc(double min, double max, double disarmed) {
  OutputChannel ch;
  ch.min = min;
  ch.max = max;
  ch.disarmed = disarmed;
  return ch;
}

TEST(OutputStage, MapsLinearlyAndNeverLeavesTheRange) {
  const OutputStage stage({esc(1150, 1924, 1000), esc(1000, 2000, 900)});
  MotorVector command(2);
  MotorVector out;
  DirectionVector dir{};
  command << 0.5, 1.0;
  stage.armed(command, out, dir, 0.0, false);
  EXPECT_NEAR(out[0], 1537.0, kExact);
  EXPECT_NEAR(out[1], 2000.0, kExact);
  command << -3.0, kNaN;
  stage.armed(command, out, dir, 0.0, false);
  EXPECT_EQ(out[0], 1150.0);
  EXPECT_EQ(out[1], 1000.0);
  command << kInf, -kInf;  // not a command: the safe end, not full power
  stage.armed(command, out, dir, 0.0, false);
  EXPECT_EQ(out[0], 1150.0);
  EXPECT_EQ(out[1], 1000.0);
  stage.disarmed(out, dir);
  EXPECT_EQ(out[0], 1000.0);
  EXPECT_EQ(out[1], 900.0);
}

TEST(OutputStage, IdleTrimReversalAndThrustModel) {
  OutputChannel ch = esc(1000, 2000, 900);
  ch.idle = 0.1;
  MotorVector command(1);
  MotorVector out;
  DirectionVector dir{};
  command << 0.0;
  OutputStage({ch}).armed(command, out, dir, 0.0, false);
  EXPECT_NEAR(out[0], 1100.0, kExact);  // armed motors keep spinning at idle
  ch.idle = 0.0;
  ch.thrust_model_factor = 1.0;  // thrust ~ x^2: a quarter thrust needs half command
  command << 0.25;
  OutputStage({ch}).armed(command, out, dir, 0.0, false);
  EXPECT_NEAR(out[0], 1500.0, kExact);
  ch.thrust_model_factor = 0.5;
  for (double t : {0.0, 0.1, 0.5, 0.9, 1.0}) {
    const double x = OutputStage::linearize(t, 0.5);
    EXPECT_NEAR(0.5 * x * x + 0.5 * x, t, kExact);
  }
  ch.thrust_model_factor = 0.0;
  ch.reversed = true;
  ch.trim = 0.05;
  command << 0.25;
  OutputStage({ch}).armed(command, out, dir, 0.0, false);
  EXPECT_NEAR(out[0], 1700.0, kExact);  // (0.25 + 0.05) reversed: 0.7
}

TEST(OutputStage, ReversibleOutputs) {
  OutputChannel centred = esc(1000, 2000, 1500);
  centred.mode = OutputMode::kCentered;
  centred.center = 1500;
  OutputChannel bridge = esc(0, 255, 0);
  bridge.mode = OutputMode::kMagnitudeDirection;
  const OutputStage stage({centred, bridge});
  MotorVector command(2);
  MotorVector out;
  DirectionVector dir{};
  command << -0.5, -0.8;
  stage.armed(command, out, dir, 0.0, false);
  EXPECT_NEAR(out[0], 1250.0, kExact);
  EXPECT_NEAR(out[1], 0.8 * 255, kExact);
  EXPECT_EQ(dir[1], -1);
  command << 1.0, 0.0;
  stage.armed(command, out, dir, 0.0, false);
  EXPECT_NEAR(out[0], 2000.0, kExact);
  EXPECT_NEAR(out[1], 0.0, kExact);
  EXPECT_EQ(dir[1], 0);
  stage.disarmed(out, dir);
  EXPECT_EQ(out[0], 1500.0);
  EXPECT_EQ(out[1], 0.0);
}

TEST(OutputStage, SlewLimitFromThePreviousArmedCycle) {
  OutputChannel ch = esc(1000, 2000, 900);
  ch.slew_per_s = 1000.0;  // 1000 us per second: 2.5 us per 400 Hz cycle
  const OutputStage stage({ch});
  MotorVector command(1);
  MotorVector out;
  DirectionVector dir{};
  command << 0.0;
  stage.armed(command, out, dir, 0.0025, false);  // first armed cycle: no history
  EXPECT_NEAR(out[0], 1000.0, kExact);
  command << 1.0;
  stage.armed(command, out, dir, 0.0025, true);
  EXPECT_NEAR(out[0], 1002.5, kExact);
  for (int k = 0; k < 1000; ++k) stage.armed(command, out, dir, 0.0025, true);
  EXPECT_NEAR(out[0], 2000.0, kExact);
}

TEST(Mixer, RefusesNonFiniteDemandWithDisarmedOutputs) {
  const Mixer mixer = config::build_mixer(team_quad_config());
  for (double bad : {kNaN, kInf, -kInf}) {
    for (int axis = 0; axis < kNumAxes; ++axis) {
      AxisVector demand(0.1, 0.1, 0.1, 0.5);
      demand[axis] = bad;
      MixerOutput out;
      EXPECT_EQ(mixer.mix(demand, out), MixStatus::kNonFiniteDemand);
      EXPECT_FALSE(out.armed);
      for (int i = 0; i < 4; ++i) EXPECT_EQ(out.output[i], 1000.0);
    }
  }
}

TEST(Mixer, ClampsOutOfRangeDemandAndSaysSo) {
  const Mixer mixer = config::build_mixer(team_quad_config());
  MixerOutput out;
  EXPECT_EQ(mixer.mix(AxisVector(5.0, 0.0, 0.0, 2.0), out), MixStatus::kDemandClamped);
  MixerOutput reference;
  EXPECT_EQ(mixer.mix(AxisVector(1.0, 0.0, 0.0, 1.0), reference), MixStatus::kOk);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(out.output[i], reference.output[i]);
}

TEST(Mixer, RandomDemandsIncludingExtremesStayInRange) {
  const Mixer mixer = config::build_mixer(team_quad_config());
  std::mt19937_64 rng(7);
  const std::array<double, 9> specials = {0.0, 1.0, -1.0, 1e308, -1e308, kNaN, kInf, -kInf, 1e-300};
  std::uniform_real_distribution<double> wide(-3.0, 3.0);
  std::uniform_int_distribution<std::size_t> pick(0, specials.size() * 3);
  MixerOutput out;
  for (int k = 0; k < 300000; ++k) {
    AxisVector demand;
    for (int a = 0; a < kNumAxes; ++a) {
      const std::size_t p = pick(rng);
      demand[a] = p < specials.size() ? specials[p] : wide(rng);
    }
    mixer.mix(demand, out);
    for (int i = 0; i < 4; ++i) {
      ASSERT_TRUE(std::isfinite(out.output[i]));
      const double lo = out.armed ? 1150.0 : 1000.0;
      const double hi = out.armed ? 1924.0 : 1000.0;
      ASSERT_GE(out.output[i], lo);
      ASSERT_LE(out.output[i], hi);
    }
  }
}

TEST(Allocation, ReportsSaturationAndUndeliveredDemand) {
  const Mixer mixer = config::build_mixer(team_quad_config());
  MixerOutput out;
  // Throttle 1, roll 1: the left motors reach full power (0.6 + 0.25 = 0.85,
  // not yet 1), the right motors sit at 0.6: none saturated...
  mixer.mix(AxisVector(1.0, 0.0, 0.0, 1.0), out);
  EXPECT_EQ(out.allocation.saturated_upper, 0U);
  // ...and with yaw too, FL reaches 1.0 exactly.
  mixer.mix(AxisVector(1.0, 0.0, 1.0, 1.0), out);
  EXPECT_EQ(out.allocation.saturated_upper, 0b0001U);
  // Roll 0.5 at zero throttle: dropping the negative half means only half of
  // the budgeted roll is produced, and thrust appears that was not asked for.
  mixer.mix(AxisVector(0.5, 0.0, 0.0, 0.0), out);
  EXPECT_NEAR(out.allocation.unallocated[index(Axis::kRoll)], 0.125 - 0.0625, kExact);
  EXPECT_NEAR(out.allocation.unallocated[index(Axis::kThrust)], -0.0625, kExact);
  EXPECT_TRUE(out.allocation.axis_limited & bit(Axis::kRoll));
  EXPECT_FALSE(out.allocation.axis_limited & bit(Axis::kPitch));
  EXPECT_EQ(out.allocation.saturated_lower, 0b1010U);  // FR and RR at zero
  // Pure throttle is delivered exactly.
  mixer.mix(AxisVector(0.0, 0.0, 0.0, 0.5), out);
  EXPECT_EQ(out.allocation.axis_limited, 0);
}

TEST(MixingMatrix, EffectivenessIsThePseudoInverse) {
  const auto config = team_quad_config();
  const EffectivenessMatrix e = effectiveness_of(config.mixing);
  const Eigen::Matrix4d product = e * config.mixing;
  EXPECT_TRUE(product.isApprox(Eigen::Matrix4d::Identity(), 1e-12));
  EXPECT_EQ(rank_of(config.mixing), 4);
  MixingMatrix degenerate(4, 4);
  degenerate << 1, 0, 1, 1, 1, 0, 1, 1, -1, 0, -1, 1, -1, 0, -1, 1;  // no pitch authority
  EXPECT_EQ(rank_of(degenerate), 2);
}

}  // namespace
}  // namespace motormix::test
