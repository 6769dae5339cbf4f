// Motor-failure reallocation: the re-derived matrices, what each strategy
// holds with motors out, and that a loss is reported rather than hidden.

#include "test_support.hpp"

#include <motormix/allocation/motor_failure.hpp>

#include <gtest/gtest.h>

#include <random>

namespace motormix::test {
namespace {

// Pseudo-inverse products: exact up to the decomposition's rounding.
constexpr double kMatrixIdentity = 1e-9;
// An active-set optimum delivers the demand to this (normalized units).
constexpr double kHoverDelivered = 1e-6;
// Rounding of a few products of normalized values.
constexpr double kReported = 1e-9;

config::Config preset(const std::string& name, const std::string& strategy) {
  return config::load_config_text(
      "geometry: {preset: " + name + "}\nmixer: {strategy: " + strategy + "}\n", name + ".yaml");
}

MotorMask motor(int i) { return MotorMask{1} << i; }

// What the working motors really produce: the healthy effectiveness with
// every failed motor's column zeroed, applied to the commands. Written out
// here, independently of the mixer's own reporting.
AxisVector produced(const config::Config& c, MotorMask failed, const MotorVector& command) {
  EffectivenessMatrix e = effectiveness_of(c.mixing);
  for (int i = 0; i < c.motors(); ++i) {
    if ((failed >> i) & 1U) e.col(i).setZero();
  }
  return e * command;
}

TEST(FailureMixing, HexaSingleFailureHoldsEveryAxisInHealthyUnits) {
  const config::Config c = preset("hexa_x", "clip");
  const EffectivenessMatrix healthy = effectiveness_of(c.mixing);
  for (int m = 0; m < 6; ++m) {
    const FailureMixing f = derive_failure_mixing(healthy, kAllAxes, motor(m));
    EXPECT_EQ(f.held, kAllAxes) << "m" << m + 1;
    EXPECT_TRUE(f.mixing.row(m).isZero(0.0)) << "the failed motor gets nothing";
    EXPECT_TRUE(f.effectiveness.col(m).isZero(0.0));
    // Healthy units: the remaining motors produce exactly the demand.
    const Eigen::Matrix4d product = f.effectiveness * f.mixing;
    EXPECT_TRUE(product.isIdentity(kMatrixIdentity)) << "m" << m + 1 << "\n" << product;
  }
}

TEST(FailureMixing, QuadGivesUpYawFirst) {
  const config::Config c = preset("quad_x", "clip");
  const FailureMixing f = derive_failure_mixing(effectiveness_of(c.mixing), kAllAxes, motor(0));
  EXPECT_EQ(f.held, bit(Axis::kRoll) | bit(Axis::kPitch) | bit(Axis::kThrust));
  EXPECT_TRUE(f.mixing.col(index(Axis::kYaw)).isZero(0.0));
  // Roll, pitch and thrust are delivered exactly by the linear mix.
  const Eigen::Matrix4d product = f.effectiveness * f.mixing;
  for (Axis a : {Axis::kRoll, Axis::kPitch, Axis::kThrust}) {
    for (Axis b : {Axis::kRoll, Axis::kPitch, Axis::kThrust}) {
      EXPECT_NEAR(product(index(a), index(b)), a == b ? 1.0 : 0.0, kMatrixIdentity);
    }
  }
}

TEST(FailureMixing, EveryPairIsPreparedAtSetUp) {
  const config::Config c = preset("octo_x", "prioritized");
  const Mixer mixer = config::build_mixer(c);
  EXPECT_EQ(mixer.failures().prepared.size(), 8U + 28U);
  for (int i = 0; i < 8; ++i) {
    ASSERT_NE(mixer.prepared(motor(i)), nullptr);
    for (int j = i + 1; j < 8; ++j) ASSERT_NE(mixer.prepared(motor(i) | motor(j)), nullptr);
  }
  EXPECT_EQ(mixer.prepared(motor(0) | motor(1) | motor(2)), nullptr);
}

// The promise for `optimal`: a hexa X or an octo X holds hover in all
// four axes with any one motor out.
TEST(FailureOptimal, HexaAndOctoHoldHoverWithAnyOneMotorOut) {
  for (const char* name : {"hexa_x", "octo_x"}) {
    const config::Config c = preset(name, "optimal");
    const Mixer mixer = config::build_mixer(c);
    for (int m = 0; m < c.motors(); ++m) {
      MixerOutput out;
      const AxisVector hover(0.0, 0.0, 0.0, 0.5);
      mixer.mix(hover, out, 0.0, motor(m));
      EXPECT_EQ(out.failure, FailureHandling::kReallocated);
      EXPECT_EQ(out.command[m], 0.0);
      const AxisVector error = hover - produced(c, motor(m), out.command);
      EXPECT_LT(error.cwiseAbs().maxCoeff(), kHoverDelivered) << name << " m" << m + 1;
      EXPECT_EQ(out.allocation.axis_limited, 0) << name << " m" << m + 1;
    }
  }
}

// `optimal` with a motor out and more yaw asked than fits (the controller's
// yaw demand grows while the vehicle turns): yaw gives way to roll and pitch
// as with `prioritized`. At the configured yaw weight (0.2 of roll's) the
// weighted trade left roll and pitch short by a quarter to two thirds here,
// and the closed-loop hexa flew 10-17 degrees off (SIM.md's target: 15).
constexpr double kYawYieldedRollPitch = 0.002;  // of a 0.05 demand: yaw's hundredth weight
TEST(FailureOptimal, YawGivesWayToRollAndPitchWithAMotorOut) {
  for (const char* name : {"hexa_x", "octo_x"}) {
    const config::Config c = preset(name, "optimal");
    const Mixer mixer = config::build_mixer(c);
    for (int m = 0; m < c.motors(); ++m) {
      MixerOutput out;
      const AxisVector demand(0.05, -0.05, 0.8, 0.5);
      mixer.mix(demand, out, 0.0, motor(m));
      const AxisVector error = demand - produced(c, motor(m), out.command);
      EXPECT_NEAR(error[index(Axis::kRoll)], 0.0, kYawYieldedRollPitch) << name << " m" << m + 1;
      EXPECT_NEAR(error[index(Axis::kPitch)], 0.0, kYawYieldedRollPitch) << name << " m" << m + 1;
      EXPECT_GT(std::abs(error[index(Axis::kYaw)]), 0.1) << "yaw gave way";
    }
  }
}

// `prioritized` with a motor out: roll, pitch and thrust are held, and yaw
// gives way first.
TEST(FailurePrioritized, HexaHoldsRollPitchThrustAndYawGivesWay) {
  const config::Config c = preset("hexa_x", "prioritized");
  const Mixer mixer = config::build_mixer(c);
  for (int m = 0; m < 6; ++m) {
    MixerOutput out;
    const AxisVector demand(0.05, -0.05, 0.8, 0.5);  // far more yaw than fits
    mixer.mix(demand, out, 0.0, motor(m));
    const AxisVector error = demand - produced(c, motor(m), out.command);
    EXPECT_NEAR(error[index(Axis::kRoll)], 0.0, kHoverDelivered) << "m" << m + 1;
    EXPECT_NEAR(error[index(Axis::kPitch)], 0.0, kHoverDelivered) << "m" << m + 1;
    EXPECT_NEAR(error[index(Axis::kThrust)], 0.0, kHoverDelivered) << "m" << m + 1;
    EXPECT_GT(std::abs(error[index(Axis::kYaw)]), 0.1) << "yaw gave way";
    EXPECT_TRUE(out.allocation.axis_limited & bit(Axis::kYaw));
    // The report agrees with the independent product.
    EXPECT_TRUE(out.allocation.unallocated.isApprox(error, kReported) ||
                (out.allocation.unallocated - error).cwiseAbs().maxCoeff() < kReported);
  }
}

// A quad cannot hold yaw with a motor out: it must say so.
TEST(FailureQuad, ReportsTheLostAxisHonestly) {
  for (const char* strategy : {"clip", "shift", "prioritized", "optimal"}) {
    const config::Config c = preset("quad_x", strategy);
    const Mixer mixer = config::build_mixer(c);
    MixerOutput out;
    const AxisVector demand(0.1, 0.0, 0.0, 0.5);
    mixer.mix(demand, out, 0.0, motor(0));
    EXPECT_EQ(out.failure, FailureHandling::kAxesLost) << strategy;
    EXPECT_FALSE(out.held & bit(Axis::kYaw)) << strategy;
    EXPECT_EQ(out.authority[index(Axis::kYaw)], 0.0) << strategy;
    const AxisVector error = demand - produced(c, motor(0), out.command);
    // The three working motors make yaw torque nobody asked for, and the
    // report says how much.
    EXPECT_GT(std::abs(error[index(Axis::kYaw)]), 0.1) << strategy;
    EXPECT_NEAR(out.allocation.unallocated[index(Axis::kYaw)], error[index(Axis::kYaw)], kReported)
        << strategy;
    EXPECT_TRUE(out.allocation.axis_limited & bit(Axis::kYaw)) << strategy;
  }
}

TEST(FailureOutputs, FailedMotorIsStoppedAndNotCalledSaturated) {
  const config::Config c = preset("hexa_x", "prioritized");
  const Mixer mixer = config::build_mixer(c);
  MixerOutput out;
  mixer.disarm(out);
  mixer.mix(AxisVector(0.3, 0.3, 0.3, 0.9), out, 0.0, motor(2));
  EXPECT_EQ(out.output[2], c.outputs[2].disarmed);
  EXPECT_EQ(out.command[2], 0.0);
  EXPECT_FALSE((out.allocation.saturated_lower | out.allocation.saturated_upper) & motor(2));
  EXPECT_EQ(out.failed, motor(2));
  // Bits beyond the motor count are ignored.
  mixer.mix(AxisVector(0.0, 0.0, 0.0, 0.5), out, 0.0, motor(9));
  EXPECT_EQ(out.failed, 0U);
  EXPECT_EQ(out.failure, FailureHandling::kNone);
}

TEST(FailureOutputs, UnpreparedSetStopsEveryFailedMotorAndPromisesNothing) {
  const config::Config c = preset("octo_x", "optimal");
  const Mixer mixer = config::build_mixer(c);
  const MotorMask three = motor(0) | motor(3) | motor(6);
  MixerOutput out;
  const AxisVector demand(0.1, 0.0, 0.0, 0.4);
  mixer.mix(demand, out, 0.0, three);
  EXPECT_EQ(out.failure, FailureHandling::kUnsupported);
  EXPECT_EQ(out.held, 0);
  for (int m : {0, 3, 6}) {
    EXPECT_EQ(out.command[m], 0.0);
    EXPECT_EQ(out.output[m], c.outputs[static_cast<std::size_t>(m)].disarmed);
  }
  const AxisVector error = demand - produced(c, three, out.command);
  EXPECT_LT((out.allocation.unallocated - error).cwiseAbs().maxCoeff(), kReported);
}

TEST(FailureOutputs, BudgetStrategiesStopTheMotorAndReportTheLoss) {
  const config::Config c = team_quad_config();
  const Mixer mixer = config::build_mixer(c);
  MixerOutput out;
  const AxisVector demand(0.2, 0.0, 0.0, 0.5);
  mixer.mix(demand, out, 0.0, motor(1));
  EXPECT_EQ(out.failure, FailureHandling::kUnsupported);
  EXPECT_EQ(out.command[1], 0.0);
  EXPECT_EQ(out.output[1], c.outputs[1].disarmed);
  const AxisVector error = demand - produced(c, motor(1), out.command);
  EXPECT_LT((out.allocation.unallocated - error).cwiseAbs().maxCoeff(), kReported);
}

// Seeded: any strategy, any failure set of up to three motors, any demand:
// outputs in range, failed motors stopped, the report true.
TEST(FailureProperties, OutputsInRangeAndReportTrue) {
  std::mt19937 rng(20261201);
  std::uniform_real_distribution<double> torque(-1.0, 1.0);
  std::uniform_real_distribution<double> thrust(0.0, 1.0);
  for (const char* name : {"quad_x", "hexa_x", "octo_x", "y6"}) {
    for (const char* strategy : {"clip", "shift", "prioritized", "optimal"}) {
      const config::Config c = preset(name, strategy);
      const Mixer mixer = config::build_mixer(c);
      const int n = c.motors();
      std::uniform_int_distribution<int> pick(0, n - 1);
      MixerOutput out;
      for (int k = 0; k < 3000; ++k) {
        MotorMask failed = 0;
        const int count = k % 4;
        for (int j = 0; j < count; ++j) failed |= motor(pick(rng));
        const AxisVector demand(torque(rng), torque(rng), torque(rng), thrust(rng));
        mixer.mix(demand, out, 0.0, failed);
        for (int i = 0; i < n; ++i) {
          const OutputChannel& ch = c.outputs[static_cast<std::size_t>(i)];
          ASSERT_TRUE(std::isfinite(out.output[i]));
          if ((failed >> i) & 1U) {
            ASSERT_EQ(out.output[i], ch.disarmed);
          } else {
            ASSERT_GE(out.output[i], ch.min);
            ASSERT_LE(out.output[i], ch.max);
          }
        }
        const AxisVector error = demand - produced(c, failed, out.command);
        ASSERT_LT((out.allocation.unallocated - error).cwiseAbs().maxCoeff(), kReported)
            << name << " " << strategy << " failed " << failed;
      }
    }
  }
}

}  // namespace
}  // namespace motormix::test
