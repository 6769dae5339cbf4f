// inputs.units: physical. A controller that asks for newtons and
// newton-metres gets them: the outputs the loop makes, pushed through the
// vehicle's rotors by hand (the ESC's curve written out, each rotor's lever
// and drag torque), give back the thrust and torques asked for.

#include "loop/control_loop.hpp"
#include "test_support.hpp"

#include <motormix/config/hover_point.hpp>

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace motormix::test {
namespace {

using loop::ControlLoop;
using loop::LoopState;
using loop::PidSample;
using loop::Rejection;
using loop::SetpointSample;

constexpr double kGravity = 9.80665;
// The torques go through the chain's slope at hover: exact to first order,
// the curvature of the ESC's curve is what is left.
constexpr double kTorqueTolerance = 0.02;  // of the torque asked
// The thrust goes through a 200-step table of the whole chain.
constexpr double kThrustTolerance = 0.002;  // of the thrust asked

struct Wrench {
  Eigen::Vector3d torque = Eigen::Vector3d::Zero();
  double thrust = 0.0;
};

// What the outputs give, worked without the loop's own chain: the ESC's
// quadratic curve over its range, then each rotor's thrust, lever and drag.
Wrench wrench_of(const config::Config& c, const Eigen::VectorXd& output) {
  Wrench w;
  const auto& v = c.vehicle_model;
  const double expo = v.thrust_expo;
  for (std::size_t i = 0; i < v.rotors.size(); ++i) {
    const double x = std::clamp(
        (output[static_cast<Eigen::Index>(i)] - v.esc_min[i]) / (v.esc_max[i] - v.esc_min[i]), 0.0,
        1.0);
    const double thrust = (expo * x * x + (1.0 - expo) * x) * v.rotors[i].max_thrust_n;
    const auto& r = v.rotors[i];
    w.torque +=
        (r.position_m.cross(r.axis) - static_cast<double>(r.spin) * r.torque_ratio_m * r.axis) *
        thrust;
    w.thrust += -r.axis.z() * thrust;
  }
  return w;
}

class PhysicalInputsTest : public ::testing::TestWithParam<const char*> {
 protected:
  config::Config config_ = config::load_config_file(
      source_path(GetParam()),
      {"inputs.units=physical", "inputs.arm_max_throttle=1", "output.spool_up_s=0",
       "vehicle.mass_kg=1.2", "vehicle.max_thrust_n=5.9", "vehicle.torque_ratio_m=0.016"});
  ControlLoop loop_{config_, config::build_mixer(config_)};
  std::int64_t utime_ = 1'700'000'000'000'000;
  std::int64_t now_ = 0;

  const loop::CycleResult& fly(double thrust_n, const Eigen::Vector3d& torque_nm) {
    now_ += kMs;
    EXPECT_EQ(loop_.on_setpoint(SetpointSample{utime_ += 1000, thrust_n, 0.0, true}, now_, kWall),
              Rejection::kNone);
    EXPECT_EQ(loop_.on_pid(PidSample{utime_ += 1000, torque_nm.x(), torque_nm.y(), torque_nm.z()},
                           now_, kWall),
              Rejection::kNone);
    return loop_.cycle(now_);
  }
  void arm() {
    now_ += kMs;
    ASSERT_EQ(loop_.on_setpoint(SetpointSample{utime_ += 1000, 0.0, 0.0, false}, now_, kWall),
              Rejection::kNone);
    ASSERT_EQ(loop_.on_pid(PidSample{utime_ += 1000, 0.0, 0.0, 0.0}, now_, kWall),
              Rejection::kNone);
    ASSERT_EQ(loop_.cycle(now_).state, LoopState::kDisarmed);
    ASSERT_EQ(fly(0.0, Eigen::Vector3d::Zero()).state, LoopState::kArmed);
  }
};

TEST_P(PhysicalInputsTest, TheThrustAskedIsTheThrustMadeFromIdleToNearFull) {
  arm();
  const double weight = config_.vehicle_model.mass_kg * kGravity;
  // 0.3 to 1.9 weights: below hover, at it, well above it (the rotors
  // give 2.0 weights in all on the quad, 3.0 on the hexa).
  for (const double weights : {0.3, 0.7, 1.0, 1.4, 1.9}) {
    const double asked = weights * weight;
    const auto& r = fly(asked, Eigen::Vector3d::Zero());
    ASSERT_EQ(r.state, LoopState::kArmed);
    const Wrench w = wrench_of(config_, r.mix.output);
    EXPECT_NEAR(w.thrust, asked, kThrustTolerance * asked) << weights << " weights";
    EXPECT_NEAR(w.torque.norm(), 0.0, 1e-9) << weights << " weights";
  }
}

TEST_P(PhysicalInputsTest, TheTorquesAskedAtHoverAreTheTorquesMade) {
  arm();
  const double weight = config_.vehicle_model.mass_kg * kGravity;
  // One axis at a time and all three together, both signs: a tenth of a
  // newton-metre of roll on this frame is a strong but unsaturated demand.
  const Eigen::Vector3d asks[] = {{0.10, 0.0, 0.0},
                                  {0.0, -0.10, 0.0},
                                  {0.0, 0.0, 0.02},
                                  {-0.06, 0.05, -0.015},
                                  {0.03, 0.03, 0.01}};
  for (const Eigen::Vector3d& asked : asks) {
    const auto& r = fly(weight, asked);
    ASSERT_EQ(r.state, LoopState::kArmed);
    ASSERT_EQ(r.mix.allocation.axis_limited, 0U) << asked.transpose();
    const Wrench w = wrench_of(config_, r.mix.output);
    for (int a = 0; a < 3; ++a) {
      EXPECT_NEAR(w.torque[a], asked[a], kTorqueTolerance * asked.norm())
          << "axis " << a << " for " << asked.transpose();
    }
    EXPECT_NEAR(w.thrust, weight, 0.01 * weight) << asked.transpose();
  }
}

TEST_P(PhysicalInputsTest, BeyondTheVehicleIsClampedNeverOutOfRange) {
  arm();
  // Ten times the rotors' total thrust, a torque no rotor can make, and
  // negative thrust: demands stay in their range, outputs in theirs.
  for (const auto& [thrust, torque] : {std::pair{1000.0, Eigen::Vector3d(50.0, -50.0, 9.0)},
                                       std::pair{-5.0, Eigen::Vector3d(0.0, 0.0, 0.0)}}) {
    const auto& r = fly(thrust, torque);
    ASSERT_EQ(r.state, LoopState::kArmed);
    for (int i = 0; i < r.mix.output.size(); ++i) {
      EXPECT_GE(r.mix.output[i], config_.outputs[static_cast<std::size_t>(i)].min);
      EXPECT_LE(r.mix.output[i], config_.outputs[static_cast<std::size_t>(i)].max);
    }
  }
  // NaN is still refused as a value, not converted.
  EXPECT_NE(loop_.on_setpoint(SetpointSample{utime_ += 1000, std::nan(""), 0.0, true}, now_, kWall),
            Rejection::kNone);
}

INSTANTIATE_TEST_SUITE_P(Frames, PhysicalInputsTest,
                         ::testing::Values("config/quad_x.yaml", "config/hexa_x.yaml"));

// Newtons need a vehicle to be turned into demands: without mass and
// thrust the configuration is refused at start-up, naming the key.
TEST(PhysicalInputsConfig, NeedsAVehicleThatHovers) {
  for (const std::vector<std::string>& set :
       {std::vector<std::string>{"inputs.units=physical"},
        std::vector<std::string>{"inputs.units=physical", "vehicle.mass_kg=30",
                                 "vehicle.max_thrust_n=5.9"}}) {
    try {
      config::load_config_file(source_path("config/quad_x.yaml"), set);
      ADD_FAILURE() << "accepted: " << set.back();
    } catch (const config::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("inputs.units"), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(
      config::load_config_file(source_path("config/quad_x.yaml"), {"inputs.units=newtons"}),
      config::ConfigError);
}

}  // namespace
}  // namespace motormix::test
