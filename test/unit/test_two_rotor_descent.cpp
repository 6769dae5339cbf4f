// The two-rotor landing: which pairs a quad can land on and why not the
// others, the regulator's gain against an independent check of the model it
// is solved for (the closed loop's eigenvalues, continuous time), its
// outputs under hostile inputs, its landing rule; and the control loop
// handing a quad with two opposite failed motors to it.

#include "loop/control_loop.hpp"
#include "test_support.hpp"

#include <motormix/safety/two_rotor_descent.hpp>

#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>

#include <cmath>
#include <limits>

namespace motormix::test {
namespace {

constexpr double kTwoRotorNaN = std::numeric_limits<double>::quiet_NaN();
// The closed loop decays at least this fast (1/s) at every spin the
// landing flies (a default quad X reaches 41 rad/s from 10 m), and is stable
// beyond. Faster spins hold the axis stiffer: at 100 rad/s tilting it at
// 0.25 rad/s takes all the differential (the precession rate is the torque
// over the spin's angular momentum), so the slowest pole there is slower.
// At no spin at all, a torque about one axis cannot turn the other: the
// angular momentum across it is conserved (the grid starts its check above).
constexpr double kMinDecayPerS = 0.5;
constexpr double kFlownSpinRadS = 48.0;

config::Config quad(const std::string& preset, std::vector<std::string> overrides = {}) {
  overrides.push_back("inputs.arm_max_throttle=1");
  return config::load_config_text("geometry: {preset: " + preset + "}\n", "test", overrides);
}

unsigned mask(int a, int b) { return (1U << a) | (1U << b); }

TEST(TwoRotorPlan, OppositePairsOfBothQuadsAndWhyNotTheOthers) {
  for (const char* preset : {"quad_x", "team_quad"}) {
    const config::Config c = quad(preset);
    ASSERT_TRUE(c.motor_loss.has_value()) << c.motor_loss_off;
    const SpinningDescentModel& m = c.motor_loss->model;
    int found = 0;
    for (int a = 0; a < 4; ++a) {
      for (int b = a + 1; b < 4; ++b) {
        SCOPED_TRACE(std::string(preset) + " motors " + std::to_string(a + 1) + "+" +
                     std::to_string(b + 1));
        const TwoRotorPlan p = plan_two_rotor_descent(m, a, b);
        // The two left: their arms opposite, their torques across cancel
        // with the shares, and they turn the body the same way.
        const auto ka = static_cast<std::size_t>(p.working[0]);
        const auto kb = static_cast<std::size_t>(p.working[1]);
        const Eigen::Vector3d across =
            p.share[0] * m.torque_per_newton[ka] + p.share[1] * m.torque_per_newton[kb];
        if (!p.found) {
          EXPECT_NE(p.why.find("not opposite"), std::string::npos) << p.why;
          continue;
        }
        ++found;
        EXPECT_NEAR(p.share[0] + p.share[1], 1.0, 1e-12);
        EXPECT_NEAR(across.head<2>().norm(), 0.0, 1e-9);
        EXPECT_EQ(m.spin[ka], m.spin[kb]);
        EXPECT_GT(across.z() * p.spin_sign, 0.0);
        // Twice the weight in thrust, 92 % of two rotors: 92 % of the weight.
        EXPECT_NEAR(p.weight_share, 0.92, 0.01);
      }
    }
    EXPECT_EQ(found, 2) << preset;
  }
}

TEST(TwoRotorPlan, SaysWhyWhenTheTwoCannotCarryTheVehicle) {
  const config::Config c = quad("quad_x", {"vehicle.max_thrust_n=5.3"});
  ASSERT_TRUE(c.motor_loss.has_value()) << c.motor_loss_off;
  const TwoRotorPlan p = plan_two_rotor_descent(c.motor_loss->model, 0, 1);
  EXPECT_FALSE(p.found);
  EXPECT_NE(p.why.find("of the weight"), std::string::npos) << p.why;
  EXPECT_NE(c.motor_loss_summary().find("two opposite motors lost: no landing"), std::string::npos)
      << c.motor_loss_summary();
}

// The continuous model the gain is solved for, written out again here:
// x = [axis error x, y; rates x, y; differential through the lag].
Eigen::Matrix<double, 5, 5> closed_loop(const SpinningDescentModel& m, const TwoRotorPlan& p,
                                        const TwoRotorDescent::Gain& k, double spin) {
  const Eigen::Vector3d& i = m.inertia_kgm2;
  const double weight = m.mass_kg * kStandardGravity;
  double hz = 0.0;
  for (std::size_t j = 0; j < 2; ++j) {
    const auto r = static_cast<std::size_t>(p.working[j]);
    const double f = p.share[j] * std::min(weight, p.weight_share * weight);
    hz += m.spin[r] * m.rotor_inertia_kgm2 * m.max_rotor_speed_rad_s *
          std::sqrt(f / m.max_thrust_n[r]) * m.axis[r].z();
  }
  const Eigen::Vector3d d = 0.5 * (m.torque_per_newton[static_cast<std::size_t>(p.working[0])] -
                                   m.torque_per_newton[static_cast<std::size_t>(p.working[1])]);
  Eigen::Matrix<double, 5, 5> a = Eigen::Matrix<double, 5, 5>::Zero();
  // The world's up seen from a body turning at w: n' = -w x n, n = (x, y, -1).
  a(0, 1) = spin;
  a(0, 3) = 1.0;
  a(1, 0) = -spin;
  a(1, 2) = -1.0;
  // Euler's equations about the spin, with the rotors' momentum and the drag.
  a(2, 2) = -m.rotational_drag / i.x();
  a(2, 3) = -(spin * (i.z() - i.y()) + hz) / i.x();
  a(2, 4) = d.x() / i.x();
  a(3, 2) = (spin * (i.z() - i.x()) + hz) / i.y();
  a(3, 3) = -m.rotational_drag / i.y();
  a(3, 4) = d.y() / i.y();
  a(4, 4) = -1.0 / m.time_constant_s;
  Eigen::Matrix<double, 5, 1> b = Eigen::Matrix<double, 5, 1>::Zero();
  b(4) = 1.0 / m.time_constant_s;
  return a - b * k;
}

TEST(TwoRotorGain, StabilizesTheModelAtEverySpinOfTheGrid) {
  const config::Config c = quad("quad_x");
  const SpinningDescentModel& m = c.motor_loss->model;
  const TwoRotorDescent descent(m, c.motor_loss->settings);
  for (unsigned failed : {mask(0, 1), mask(2, 3)}) {
    const TwoRotorPlan* p = descent.plan(failed);
    ASSERT_NE(p, nullptr);
    ASSERT_TRUE(p->found) << p->why;
    for (double spin = 4.0; spin <= TwoRotorDescent::kGridTopRadS; spin += 4.0) {
      const double signed_spin = p->spin_sign * spin;
      const TwoRotorDescent::Gain k = descent.gain(failed, signed_spin);
      ASSERT_TRUE(k.allFinite());
      const Eigen::VectorXcd poles = closed_loop(m, *p, k, signed_spin).eigenvalues();
      for (Eigen::Index j = 0; j < poles.size(); ++j) {
        EXPECT_LT(poles[j].real(), spin <= kFlownSpinRadS ? -kMinDecayPerS : 0.0)
            << "spin " << spin << " pole " << poles[j];
      }
    }
  }
}

TEST(TwoRotorGain, WithoutRotorMomentumTheSlowestSpinTakesTheNextGain) {
  // No spin and no rotor momentum: one torque cannot steer both axes.
  const config::Config c = quad("quad_x", {"vehicle.rotor_inertia_kgm2=0"});
  const TwoRotorDescent descent(c.motor_loss->model, c.motor_loss->settings);
  const TwoRotorDescent::Gain at_rest = descent.gain(mask(0, 1), 0.0);
  EXPECT_TRUE(at_rest.allFinite());
  EXPECT_GT(at_rest.norm(), 0.0);
}

class TwoRotorDescentTest : public ::testing::Test {
 protected:
  config::Config c_ = quad("quad_x");
  TwoRotorDescent d_{c_.motor_loss->model, c_.motor_loss->settings};
  std::int64_t now_ = 0;

  // Takes over from four motors at half thrust with `failed` stopped.
  void start_at_hover(unsigned failed) {
    MotorVector hover(4);
    hover.setConstant(0.5);
    d_.start(failed, now_, hover);
  }

  const DescentCommand& step(const DescentInput& in) {
    now_ += 2500;
    return d_.update(in, now_);
  }
};

TEST_F(TwoRotorDescentTest, HostileInputsGiveThrustsInsideTheMotorsRange) {
  start_at_hover(mask(0, 1));
  ASSERT_TRUE(d_.running());
  const SpinningDescentModel& m = c_.motor_loss->model;
  std::vector<DescentInput> inputs(6);
  inputs[0].rates = {kTwoRotorNaN, 0.0, 0.0};
  inputs[1].attitude = Eigen::Quaterniond(kTwoRotorNaN, 0.0, 0.0, 0.0);
  inputs[2].rates = {1e9, -1e9, 1e9};
  inputs[3].velocity = {1e9, -1e9, 1e9};
  inputs[4].attitude = Eigen::Quaterniond(0.0, 1.0, 0.0, 0.0);  // upside down
  inputs[5].throttle = kTwoRotorNaN;
  for (const DescentInput& in : inputs) {
    const DescentCommand& cmd = step(in);
    EXPECT_EQ(cmd.thrust_fraction[0], 0.0);
    EXPECT_EQ(cmd.thrust_fraction[1], 0.0);
    for (int k = 2; k < 4; ++k) {
      EXPECT_TRUE(std::isfinite(cmd.thrust_fraction[k]));
      EXPECT_GE(cmd.thrust_fraction[k] * m.max_thrust_n[static_cast<std::size_t>(k)],
                m.min_thrust_n[static_cast<std::size_t>(k)] - 1e-12);
      EXPECT_LE(cmd.thrust_fraction[k], 1.0 + 1e-12);
    }
  }
}

TEST_F(TwoRotorDescentTest, TiltedItSteersWithTheDifferentialAndKeepsTheCollective) {
  start_at_hover(mask(0, 1));
  DescentInput in;
  in.velocity = {0.0, 0.0, 1.0};  // at the descent rate
  const DescentCommand& level = step(in);
  const double sum_level = level.thrust_n[0] + level.thrust_n[1];
  // Rolled 10 degrees right: the differential is no longer zero.
  in.attitude = Eigen::AngleAxisd(10.0 * 3.14159265358979 / 180.0, Eigen::Vector3d::UnitX());
  const DescentCommand& tilted = step(in);
  EXPECT_GT(std::abs(tilted.thrust_n[0] - tilted.thrust_n[1]), 0.05);
  EXPECT_GT(sum_level, 0.5 * c_.motor_loss->model.mass_kg * kStandardGravity);
}

TEST_F(TwoRotorDescentTest, LandsOnceStillAfterTheDescent) {
  start_at_hover(mask(2, 3));
  DescentInput in;
  in.velocity = {0.0, 0.0, 1.5};
  for (int k = 0; k < 400; ++k) EXPECT_EQ(step(in).phase, DescentPhase::kDescending);  // 1 s down
  in.velocity = {0.0, 0.0, 0.0};
  int cycles = 0;
  while (step(in).phase == DescentPhase::kDescending && cycles < 1000) ++cycles;
  EXPECT_EQ(d_.command().phase, DescentPhase::kLanded);
  EXPECT_NEAR(cycles * 0.0025, c_.motor_loss->settings.landed_after_s, 0.01);
  EXPECT_EQ(d_.command().thrust_fraction.norm(), 0.0);
}

TEST_F(TwoRotorDescentTest, HoveringAfterTheTakeOverIsNotLanded) {
  start_at_hover(mask(0, 1));
  DescentInput in;
  in.velocity = {0.0, 0.0, 0.0};
  in.rates = {0.0, 0.0, 3.0};  // turning: in the air
  for (int k = 0; k < 800; ++k) EXPECT_EQ(step(in).phase, DescentPhase::kDescending);
}

TEST(TwoRotorLoop, TwoOppositeFailedMotorsAreHandedToTheTwoRotorLanding) {
  const config::Config c = quad("quad_x", {"output.spool_up_s=0"});
  loop::ControlLoop l(c, config::build_mixer(c));
  std::int64_t now = 1'000'000, utime = 1'700'000'000'000'000;
  const auto cycle = [&](bool armed, MotorMask failed) -> const loop::CycleResult& {
    now += 2500;
    utime += 2500;
    l.on_setpoint(loop::SetpointSample{utime, 0.5, 0.0, armed}, now, kWall);
    l.on_pid(loop::PidSample{utime, 0.0, 0.0, 0.0}, now, kWall);
    l.on_motor_status(loop::MotorStatusSample{utime, 4, failed}, now, kWall);
    loop::AttitudeSample a;
    a.utime = utime;
    a.velocity = {0.0, 0.0, 0.0};
    l.on_attitude(a, now, kWall);
    return l.cycle(now);
  };
  cycle(false, 0);
  cycle(true, 0);
  const loop::CycleResult& r = cycle(true, 0b0011);
  EXPECT_EQ(r.landing.state, DescentPhase::kDescending);
  EXPECT_EQ(r.landing.motor, 0);
  EXPECT_EQ(r.landing.failed, 0b0011U);
  for (int i = 0; i < 2; ++i)
    EXPECT_EQ(r.mix.output[i], c.outputs[static_cast<std::size_t>(i)].disarmed);
  for (int i = 2; i < 4; ++i) {
    EXPECT_GE(r.mix.output[i], c.outputs[static_cast<std::size_t>(i)].min);
    EXPECT_LE(r.mix.output[i], c.outputs[static_cast<std::size_t>(i)].max);
  }
  // A third motor: nothing left to land on.
  EXPECT_EQ(cycle(true, 0b0111).landing.state, DescentPhase::kOff);
}

}  // namespace
}  // namespace motormix::test
