// The spin landing: the relaxed-hover equilibrium against an independent
// solution of the same equations, the controller at and around it, its
// outputs under hostile inputs, its landing detector; the `motor_loss:`
// section; and the control loop handing a quad with one failed motor to it
// (only with a fresh attitude, back when the attitude goes stale, disarming
// once landed).

#include "loop/control_loop.hpp"
#include "test_support.hpp"

#include <motormix/angles.hpp>
#include <motormix/safety/spinning_descent.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>

namespace motormix::test {
namespace {

constexpr double kSpinNaN = std::numeric_limits<double>::quiet_NaN();
// The equilibrium's equations hold to this (N m, N, rad/s).
constexpr double kEquationTolerance = 1e-6;
// The two solutions of the same equations agree to this.
constexpr double kAgreementTolerance = 1e-4;

config::Config spin_quad(const std::string& preset, std::vector<std::string> overrides = {}) {
  overrides.push_back("inputs.arm_max_throttle=1");
  return config::load_config_text("geometry: {preset: " + preset + "}\n", "test", overrides);
}

TEST(SpinEquilibrium, HoldsItsEquationsForEveryMotorOfBothQuads) {
  for (const char* preset : {"quad_x", "quad_plus", "team_quad"}) {
    const config::Config c = spin_quad(preset);
    ASSERT_TRUE(c.motor_loss.has_value()) << preset << ": " << c.motor_loss_off;
    const SpinningDescentModel& m = c.motor_loss->model;
    for (int failed = 0; failed < 4; ++failed) {
      SCOPED_TRACE(std::string(preset) + " motor " + std::to_string(failed + 1));
      const SpinEquilibrium eq = solve_spin_equilibrium(m, failed, 20.0);
      ASSERT_TRUE(eq.found) << eq.why;
      Eigen::Vector3d torque = Eigen::Vector3d::Zero(), force = Eigen::Vector3d::Zero();
      for (int j = 0; j < 3; ++j) {
        const auto k = static_cast<std::size_t>(eq.working[static_cast<std::size_t>(j)]);
        torque += m.torque_per_newton[k] * eq.thrust_n[j];
        force += m.axis[k] * eq.thrust_n[j];
      }
      // The rotors' own momentum (the presets' rotors have inertia): each
      // working rotor about its axis at its thrust's speed.
      Eigen::Vector3d h = Eigen::Vector3d::Zero();
      for (int j = 0; j < 3; ++j) {
        const auto k = static_cast<std::size_t>(eq.working[static_cast<std::size_t>(j)]);
        h += m.spin[k] * m.rotor_inertia_kgm2 * m.max_rotor_speed_rad_s *
             std::sqrt(eq.thrust_n[j] / m.max_thrust_n[k]) * m.axis[k];
      }
      EXPECT_GT(h.norm(), 0.0);
      const Eigen::Vector3d w = eq.rates;
      const Eigen::Vector3d holding =
          w.cross(m.inertia_kgm2.cwiseProduct(w) + h) + m.rotational_drag * w;
      EXPECT_NEAR((torque - holding).norm(), 0.0, kEquationTolerance);
      EXPECT_NEAR(eq.up.dot(force), m.mass_kg * kStandardGravity, kEquationTolerance);
      EXPECT_NEAR(w.norm(), 20.0, kEquationTolerance);
      EXPECT_NEAR(std::abs(eq.up.dot(w.normalized())), 1.0, kEquationTolerance);
      // A few degrees between the spin axis and the thrust axis, as Mueller
      // and D'Andrea find for a quad of this size.
      EXPECT_GT(eq.axis_tilt_deg, 1.0);
      EXPECT_LT(eq.axis_tilt_deg, 20.0);
    }
  }
}

TEST(SpinEquilibrium, AgreesWithTheReducedSolutionOfThePlusQuad) {
  // The reduced model leaves the rotors' momentum out: so does the vehicle.
  const config::Config c = spin_quad("quad_plus", {"vehicle.rotor_inertia_kgm2=0"});
  const SpinningDescentModel& m = c.motor_loss->model;
  const int failed = 0;
  const SpinEquilibrium eq = solve_spin_equilibrium(m, failed, 20.0);
  ASSERT_TRUE(eq.found) << eq.why;
  // Reduced model: neighbours share n, the opposite motor gives o; yaw
  // torque kappa (2n - o) = c r (up to the sign of the spin); vertical
  // force (2n + o) cos = m g; the roll torque l o balances the gyroscopic
  // torque q r (Izz - Ixx) + c p with the small drag terms. Bisection on o
  // with n from the vertical force, p and q from the two torque equations.
  // The opposite motor: the farthest from the failed one (the torque per
  // newton across the axis is the arm turned by 90 degrees).
  int opposite = 1;
  for (int k = 1; k < 4; ++k) {
    const auto dist = [&](int i) {
      return (m.torque_per_newton[static_cast<std::size_t>(i)].head<2>() -
              m.torque_per_newton[static_cast<std::size_t>(failed)].head<2>())
          .norm();
    };
    if (dist(k) > dist(opposite)) opposite = k;
  }
  const double l = m.torque_per_newton[static_cast<std::size_t>(opposite)].head<2>().norm();
  const double kappa = std::abs(m.torque_per_newton[static_cast<std::size_t>(opposite)].z());
  const double a = m.inertia_kgm2.z() - m.inertia_kgm2.x();
  const double c_drag = m.rotational_drag;
  const double weight = m.mass_kg * kStandardGravity;
  double r = 20.0;
  double lo = 0.0, hi = weight;
  double o = 0.0, n = 0.0;
  for (int it = 0; it < 200; ++it) {
    o = 0.5 * (lo + hi);
    // Across-axis rate that balances the opposite motor's torque: |w_perp|
    // = l o / sqrt((r a)^2 + c^2); the spin and the tilt follow.
    const double perp = l * o / std::sqrt(r * a * r * a + c_drag * c_drag);
    r = std::sqrt(20.0 * 20.0 - perp * perp);
    const double cos_axis = r / 20.0;
    n = (weight / cos_axis - o) / 2.0;
    const double yaw_excess = kappa * (2.0 * n - o) - c_drag * r;
    (yaw_excess > 0.0 ? lo : hi) = o;
  }
  double newton_opposite = -1.0;
  for (int j = 0; j < 3; ++j) {
    if (eq.working[static_cast<std::size_t>(j)] == opposite) newton_opposite = eq.thrust_n[j];
  }
  EXPECT_NEAR(newton_opposite, o, kAgreementTolerance);
  for (int j = 0; j < 3; ++j) {
    if (eq.working[static_cast<std::size_t>(j)] != opposite) {
      EXPECT_NEAR(eq.thrust_n[j], n, kAgreementTolerance);
    }
  }
  EXPECT_NEAR(std::abs(eq.rates.z()), r, kAgreementTolerance);
}

// A vehicle with no relaxed hover at the default spin rate: unnamed, the
// rate is chosen for it (the middle of the whole rates that have one, each
// of them checked here); named, it stands, the mode is off and the message
// names the rates that would do.
TEST(SpinEquilibrium, TheSpinRateIsChosenForAVehicleTheDefaultDoesNotFit) {
  const std::string drag = "vehicle.drag.rotational=0.01";
  const config::Config chosen = spin_quad("quad_x", {drag});
  ASSERT_TRUE(chosen.motor_loss.has_value()) << chosen.motor_loss_summary();
  const double rate = chosen.motor_loss->settings.spin_rate_rad_s;
  EXPECT_NE(rate, 20.0);
  EXPECT_NE(chosen.motor_loss->spin_rate_chosen.find("chosen"), std::string::npos);
  EXPECT_NE(chosen.motor_loss_summary().find(chosen.motor_loss->spin_rate_chosen),
            std::string::npos);
  for (const SpinEquilibrium& eq : chosen.motor_loss->equilibria) EXPECT_TRUE(eq.found);
  // Every whole rate within a rad/s of it has an equilibrium too (it is
  // away from the edges of the run), and the default has none.
  const SpinningDescentModel& m = chosen.motor_loss->model;
  for (double w : {std::floor(rate - 0.5), std::ceil(rate + 0.5)}) {
    for (int motor = 0; motor < 4; ++motor)
      EXPECT_TRUE(solve_spin_equilibrium(m, motor, w).found) << w << " rad/s, motor " << motor + 1;
  }
  bool all_at_default = true;
  for (int motor = 0; motor < 4; ++motor)
    all_at_default = all_at_default && solve_spin_equilibrium(m, motor, 20.0).found;
  EXPECT_FALSE(all_at_default);

  const config::Config named = spin_quad("quad_x", {drag, "motor_loss.spin_rate_rad_s=20"});
  EXPECT_FALSE(named.motor_loss.has_value());
  EXPECT_NE(named.motor_loss_summary().find("this vehicle has one at"), std::string::npos)
      << named.motor_loss_summary();
  // The bundled vehicles keep the default.
  EXPECT_EQ(spin_quad("quad_x").motor_loss->settings.spin_rate_rad_s, 20.0);
  EXPECT_TRUE(spin_quad("quad_x").motor_loss->spin_rate_chosen.empty());
}

TEST(SpinEquilibrium, SaysWhyWhenTheVehicleCannotHover) {
  // Thrust to weight 1.2: three motors cannot carry it; `auto` turns the
  // mode off and says why.
  const config::Config c = spin_quad("quad_x", {"vehicle.max_thrust_n=3.6"});
  ASSERT_FALSE(c.motor_loss.has_value());
  EXPECT_NE(c.motor_loss_summary().find("outside"), std::string::npos) << c.motor_loss_summary();
  EXPECT_THROW(spin_quad("quad_x", {"vehicle.max_thrust_n=3.6", "motor_loss.mode=spin_landing"}),
               config::ConfigError);
  SpinningDescentModel m = spin_quad("quad_x").motor_loss->model;
  for (double& t : m.max_thrust_n) t = 3.6;
  const SpinEquilibrium eq = solve_spin_equilibrium(m, 0, 20.0);
  EXPECT_FALSE(eq.found);
  EXPECT_NE(eq.why.find("outside"), std::string::npos) << eq.why;
}

class SpinningDescentTest : public ::testing::Test {
 protected:
  config::Config config_ = spin_quad("quad_x");
  SpinningDescent descent_{config_.motor_loss->model, config_.motor_loss->settings};

  // Each motor's thrust fraction at the equilibrium (the dead one 0).
  MotorVector equilibrium_fractions(int failed) const {
    const SpinEquilibrium& eq = descent_.equilibrium(failed);
    MotorVector x = MotorVector::Zero(4);
    for (int j = 0; j < 3; ++j) {
      const auto k = static_cast<std::size_t>(eq.working[static_cast<std::size_t>(j)]);
      x[static_cast<Eigen::Index>(k)] = eq.thrust_n[j] / config_.motor_loss->model.max_thrust_n[k];
    }
    return x;
  }

  // The vehicle exactly at the equilibrium with motor `failed` stopped:
  // spin axis vertical, rates as solved, descending at the set rate.
  DescentInput at_equilibrium(int failed) const {
    const SpinEquilibrium& eq = descent_.equilibrium(failed);
    DescentInput in;
    in.attitude = Eigen::Quaterniond::FromTwoVectors(eq.up, Eigen::Vector3d(0, 0, -1));
    in.rates = eq.rates;
    in.velocity = {0.0, 0.0, config_.motor_loss->settings.descent_rate_mps};
    return in;
  }
};

TEST_F(SpinningDescentTest, AtTheEquilibriumAsksForTheEquilibriumThrusts) {
  for (int failed = 0; failed < 4; ++failed) {
    descent_.start(failed, 0, equilibrium_fractions(failed));
    const SpinEquilibrium& eq = descent_.equilibrium(failed);
    const DescentCommand& c = descent_.update(at_equilibrium(failed), 2500);
    EXPECT_EQ(c.phase, DescentPhase::kDescending);
    EXPECT_FALSE(c.saturated);
    EXPECT_NEAR(c.axis_error_deg, 0.0, 1e-6);
    EXPECT_EQ(c.thrust_fraction[failed], 0.0);
    // Descending at the set rate needs the weight, so the same thrusts.
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(c.thrust_n[j], eq.thrust_n[j], 1e-6);
  }
}

TEST_F(SpinningDescentTest, TurnsTheSpinAxisBackUp) {
  descent_.start(1, 0, equilibrium_fractions(1));
  DescentInput in = at_equilibrium(1);
  const SpinEquilibrium& eq = descent_.equilibrium(1);
  // The spin axis tipped 10 degrees about north: the torque asked across
  // the axis points back (the thrusts leave the equilibrium's).
  in.attitude = Eigen::AngleAxisd(10.0 * kRadPerDeg, Eigen::Vector3d::UnitX()) * in.attitude;
  const DescentCommand& c = descent_.update(in, 2500);
  EXPECT_NEAR(c.axis_error_deg, 10.0, 1e-6);
  EXPECT_GT((c.thrust_n - eq.thrust_n).norm(), 0.1);
}

// Before the spin is reached the two motors beside the dead one are raised
// together as far as their range allows: both tilting torques stay what the
// controller asked, the yaw torque (the spin-up) grows. The raise fades out
// as the vehicle climbs toward the descent rate, and there is none without a
// velocity or once the spin is reached.
TEST_F(SpinningDescentTest, TheSpinUpRaisesTheMotorsBesideTheDeadOneTogether) {
  constexpr double kTorqueToleranceNm = 1e-9;
  constexpr double kRangeToleranceN = 1e-9;
  const SpinningDescentModel& m = config_.motor_loss->model;
  const double rate = config_.motor_loss->settings.descent_rate_mps;
  const int failed = 1;
  const SpinEquilibrium& eq = descent_.equilibrium(failed);
  // Just taken over: upright, not spinning yet, at hover thrust.
  const MotorVector hover = MotorVector::Constant(4, 0.35);
  const auto fly = [&](double velocity_down) {
    descent_.start(failed, 0, hover);
    DescentInput in;
    in.velocity = {0.0, 0.0, velocity_down};
    const DescentCommand c = descent_.update(in, 2500);
    EXPECT_FALSE(c.saturated);
    Eigen::Vector3d torque = Eigen::Vector3d::Zero();
    for (int j = 0; j < 3; ++j) {
      torque +=
          m.torque_per_newton[static_cast<std::size_t>(eq.working[static_cast<std::size_t>(j)])] *
          c.thrust_n[j];
    }
    return std::make_pair(c.thrust_n, torque);
  };
  const auto [descending, descending_torque] = fly(rate);   // full raise
  const auto [climbing, climbing_torque] = fly(-rate);      // none
  const auto [halfway, halfway_torque] = fly(-0.5 * rate);  // half
  // Raised to the range's edge: a motor at its most or its least.
  bool at_edge = false;
  for (int j = 0; j < 3; ++j) {
    const auto k = static_cast<std::size_t>(eq.working[static_cast<std::size_t>(j)]);
    at_edge = at_edge || descending[j] >= m.max_thrust_n[k] - kRangeToleranceN ||
              descending[j] <= m.min_thrust_n[k] + kRangeToleranceN;
  }
  EXPECT_TRUE(at_edge) << descending.transpose();
  // The velocity changes the collective, not the torques asked for.
  EXPECT_NEAR(descending_torque.x(), climbing_torque.x(), kTorqueToleranceNm);
  EXPECT_NEAR(descending_torque.y(), climbing_torque.y(), kTorqueToleranceNm);
  EXPECT_NEAR(halfway_torque.x(), climbing_torque.x(), kTorqueToleranceNm);
  // More thrust and more yaw torque, the more room the climb leaves.
  EXPECT_GT(descending.sum(), halfway.sum());
  EXPECT_GT(halfway.sum(), climbing.sum());
  EXPECT_GT(std::abs(descending_torque.z()), std::abs(halfway_torque.z()));
  EXPECT_GT(std::abs(halfway_torque.z()), std::abs(climbing_torque.z()));
  // The raise ends after twice the spin-up the model gives, reached or not:
  // a vehicle whose spin falls short of it still comes down.
  const double allowed = descent_.spin_up_s(failed);
  std::cout << "spin-up raise for at most " << allowed << " s\n";
  EXPECT_GT(allowed, 0.5);
  EXPECT_LT(allowed, 10.0);
  descent_.start(failed, 0, hover);
  DescentInput late;
  late.velocity = {0.0, 0.0, rate};
  const std::int64_t after_us = static_cast<std::int64_t>(allowed * 1e6) + 2500;
  std::int64_t now_us = 0;
  while (now_us < after_us) descent_.update(late, now_us += 2500);
  double late_sum = 0.0;
  for (int k = 0; k < 4; ++k) late_sum += descent_.command().thrust_fraction[k];
  descent_.start(failed, 0, hover);
  double early_sum = 0.0;
  descent_.update(late, 2500);
  for (int k = 0; k < 4; ++k) early_sum += descent_.command().thrust_fraction[k];
  EXPECT_LT(late_sum, early_sum);
  // Without a velocity: no raise (the climb could not be bounded).
  descent_.start(failed, 0, hover);
  DescentInput blind;
  blind.velocity.setConstant(kSpinNaN);
  blind.throttle = 0.5;
  const DescentCommand& c = descent_.update(blind, 2500);
  double full = 0.0;
  for (double t : m.max_thrust_n) full += t;
  ASSERT_FALSE(c.saturated);
  EXPECT_NEAR(c.thrust_n.sum(), blind.throttle * full,
              kRangeToleranceN);  // the throttle's, no more
}

TEST_F(SpinningDescentTest, BrakesTheDriftOnlyOnceTheSpinIsReached) {
  // Drifting at 5 m/s: braking tilts the axis by max_tilt (8 degrees, the
  // brake asked is larger than the cap). Not before the spin is up.
  constexpr double kBrakeTiltToleranceDeg = 0.5;
  const double max_tilt = config_.motor_loss->settings.max_tilt_deg;
  descent_.start(1, 0, equilibrium_fractions(1));
  DescentInput in = at_equilibrium(1);
  in.velocity.x() = 5.0;
  DescentInput still = in;
  still.rates = Eigen::Vector3d::Zero();  // just taken over: no spin yet
  EXPECT_NEAR(descent_.update(still, 2500).axis_error_deg, 0.0, 1e-6);
  EXPECT_NEAR(descent_.update(in, 5000).axis_error_deg, max_tilt, kBrakeTiltToleranceDeg);
  // Once reached, a spin lost for a moment (a gust) keeps braking.
  EXPECT_NEAR(descent_.update(still, 7500).axis_error_deg, max_tilt, kBrakeTiltToleranceDeg);
}

// "Reached" is 60 % of the equilibrium's spin (the documented share): a
// spin at 45 % of it does not brake yet, one at 75 % does.
TEST_F(SpinningDescentTest, TheSpinCountsAsReachedAtSixtyPercent) {
  constexpr double kBrakeTiltToleranceDeg = 0.5;
  constexpr double kBelow = 0.45, kAbove = 0.75;
  const double max_tilt = config_.motor_loss->settings.max_tilt_deg;
  descent_.start(1, 0, equilibrium_fractions(1));
  DescentInput in = at_equilibrium(1);
  in.velocity.x() = 5.0;
  const Eigen::Vector3d spin = in.rates;
  in.rates = kBelow * spin;
  std::int64_t t = 0;
  for (int k = 0; k < 40; ++k) descent_.update(in, t += 2500);
  EXPECT_NEAR(descent_.command().axis_error_deg, 0.0, 1e-6);
  in.rates = kAbove * spin;
  EXPECT_NEAR(descent_.update(in, t += 2500).axis_error_deg, max_tilt, kBrakeTiltToleranceDeg);
}

TEST_F(SpinningDescentTest, HostileInputsGiveThrustsInsideTheMotorsRange) {
  descent_.start(2, 0, equilibrium_fractions(2));
  const DescentInput good = at_equilibrium(2);
  std::int64_t t = 0;
  for (const double bad : {kSpinNaN, std::numeric_limits<double>::infinity(), 1e9, -1e9}) {
    for (int field = 0; field < 4; ++field) {
      DescentInput in = good;
      if (field == 0) in.rates.x() = bad;
      if (field == 1) in.velocity.z() = bad;
      if (field == 2) in.attitude.coeffs().setConstant(bad);
      if (field == 3) in.throttle = bad;
      const DescentCommand& c = descent_.update(in, t += 2500);
      for (int i = 0; i < 4; ++i) {
        EXPECT_TRUE(std::isfinite(c.thrust_fraction[i])) << "field " << field << " value " << bad;
        EXPECT_GE(c.thrust_fraction[i], 0.0);
        EXPECT_LE(c.thrust_fraction[i], 1.0);
      }
    }
  }
}

TEST_F(SpinningDescentTest, LandsOnlyOnceStillWithLittleThrustAskedFor) {
  descent_.start(0, 0, equilibrium_fractions(0));
  DescentInput in = at_equilibrium(0);
  std::int64_t t = 0;
  // Descending: never landed.
  for (int k = 0; k < 800; ++k) descent_.update(in, t += 2500);
  EXPECT_EQ(descent_.command().phase, DescentPhase::kDescending);
  // Stopped in the air for a moment (a gust from below): the velocity loop
  // still asks for about the weight at first: not landed within 0.2 s.
  in.velocity.setZero();
  for (int k = 0; k < 80; ++k) descent_.update(in, t += 2500);
  EXPECT_EQ(descent_.command().phase, DescentPhase::kDescending);
  // On the ground: the integral takes the thrust down, then landed.
  for (int k = 0; k < 800 && descent_.command().phase != DescentPhase::kLanded; ++k)
    descent_.update(in, t += 2500);
  EXPECT_EQ(descent_.command().phase, DescentPhase::kLanded);
  EXPECT_EQ(descent_.command().thrust_fraction.sum(), 0.0);
}

// Still on the ground, it lands landed_after_s after the thrust asked for
// falls under the touchdown share of the weight: the same descent with
// twice the setting lands exactly one landed_after_s later. And stopped
// for longer than landed_after_s, the velocity loop still asks for more
// than that share at first (85 % of the weight the moment it stops, the
// integral taking it under 80 % some 0.3 s later): not landed yet.
TEST(SpinningDescentLanding, LandsLandedAfterSecondsOnceStillWithLittleThrust) {
  const auto landed_after_stop = [](double landed_after_s) {
    config::Config c = spin_quad("quad_x");
    c.motor_loss->settings.landed_after_s = landed_after_s;
    SpinningDescent d(c.motor_loss->model, c.motor_loss->settings);
    const SpinEquilibrium& eq = d.equilibrium(0);
    MotorVector x = MotorVector::Zero(4);
    for (int j = 0; j < 3; ++j) {
      const auto k = static_cast<std::size_t>(eq.working[static_cast<std::size_t>(j)]);
      x[static_cast<Eigen::Index>(k)] = eq.thrust_n[j] / c.motor_loss->model.max_thrust_n[k];
    }
    d.start(0, 0, x);
    DescentInput in;
    in.attitude = Eigen::Quaterniond::FromTwoVectors(eq.up, Eigen::Vector3d(0, 0, -1));
    in.rates = eq.rates;
    in.velocity = {0.0, 0.0, c.motor_loss->settings.descent_rate_mps};
    std::int64_t t = 0;
    for (int k = 0; k < 800; ++k) d.update(in, t += 2500);  // 2 s down
    in.velocity.setZero();
    const std::int64_t stopped = t;
    while (d.command().phase != DescentPhase::kLanded && t < stopped + 5'000'000)
      d.update(in, t += 2500);
    return static_cast<double>(t - stopped) / 1e6;
  };
  constexpr double kSetting = 0.5;
  constexpr double kNotBeforeS = 0.2;  // beyond landed_after_s: the thrust's fall
  const double once = landed_after_stop(kSetting), twice = landed_after_stop(2 * kSetting);
  EXPECT_GT(once, kSetting + kNotBeforeS);
  EXPECT_NEAR(twice - once, kSetting, 2 * 2500 / 1e6);
}

TEST_F(SpinningDescentTest, TouchdownIsTheSpinLostWhileStill) {
  descent_.start(0, 0, equilibrium_fractions(0));
  DescentInput in = at_equilibrium(0);
  std::int64_t t = 0;
  for (int k = 0; k < 400; ++k) descent_.update(in, t += 2500);  // spinning down at the rate
  ASSERT_EQ(descent_.command().phase, DescentPhase::kDescending);
  // The ground stops the vehicle and takes its spin: landed at once.
  in.velocity.setZero();
  in.rates.setZero();
  EXPECT_EQ(descent_.update(in, t += 2500).phase, DescentPhase::kLanded);
}

TEST_F(SpinningDescentTest, HoveringRightAfterTheTakeOverIsNotLanded) {
  // Still, the spin building up (a quarter of the equilibrium's), the
  // velocity loop asking ever less thrust: in the air, not landed, however
  // long (the rule that lands it needs the descent flown or no turning).
  descent_.start(0, 0, equilibrium_fractions(0));
  DescentInput in = at_equilibrium(0);
  in.velocity.setZero();
  in.rates *= 0.25;
  std::int64_t t = 0;
  for (int k = 0; k < 1200; ++k) descent_.update(in, t += 2500);
  EXPECT_EQ(descent_.command().phase, DescentPhase::kDescending);
}

TEST(SpinningDescentGains, TheRateLoopLeavesFortyFiveDegreesToTheLagAndTheDelay) {
  config::Config c = spin_quad("quad_x");
  SpinningDescentModel m = c.motor_loss->model;
  const SpinningDescentSettings& s = c.motor_loss->settings;
  // A 40 ms motor lag and a 40 Hz gyro filter's 5.6 ms.
  m.time_constant_s = 0.04;
  m.rate_delay_s = 0.0056;
  const SpinningDescent slow(m, s);
  const double g = slow.rate_gain();
  EXPECT_NEAR(std::atan(g * m.time_constant_s) + g * m.rate_delay_s, std::atan(1.0), 1e-6);
  EXPECT_LT(g, s.rate_gain);
  EXPECT_NEAR(slow.attitude_gain(), g / 2.5, 1e-9);
  // Fast motors, no delay: the settings' own gains.
  m.time_constant_s = 0.01;
  m.rate_delay_s = 0.0;
  const SpinningDescent fast(m, s);
  EXPECT_EQ(fast.rate_gain(), s.rate_gain);
  EXPECT_EQ(fast.attitude_gain(), s.attitude_gain);
}

TEST_F(SpinningDescentTest, WithoutVelocityTheThrottleIsTheCollective) {
  descent_.start(3, 0, equilibrium_fractions(3));
  DescentInput in = at_equilibrium(3);
  in.velocity.setConstant(kSpinNaN);
  in.throttle = 0.5;
  const DescentCommand& half = descent_.update(in, 2500);
  const double at_half = half.thrust_n.sum();
  in.throttle = 0.3;
  const double at_less = descent_.update(in, 5000).thrust_n.sum();
  EXPECT_GT(at_half, at_less);
  // Never landed without a velocity: the flight controller disarms.
  for (int k = 0; k < 2000; ++k) descent_.update(in, 5000 + 2500 * (k + 1));
  EXPECT_EQ(descent_.command().phase, DescentPhase::kDescending);
}

TEST(MotorLossConfig, DefaultsOnForQuadsAndSaysWhyNotElsewhere) {
  EXPECT_TRUE(spin_quad("quad_x").motor_loss.has_value());
  const config::Config hexa = spin_quad("hexa_x");
  EXPECT_FALSE(hexa.motor_loss.has_value());
  EXPECT_TRUE(hexa.motor_loss_summary().empty());
  const config::Config off = spin_quad("quad_x", {"motor_loss.mode=off"});
  EXPECT_FALSE(off.motor_loss.has_value());
  EXPECT_NE(off.motor_loss_summary().find("off"), std::string::npos);
}

TEST(MotorLossConfig, RejectionsNameTheKeyTheValueAndTheRange) {
  try {
    spin_quad("hexa_x", {"motor_loss.mode=spin_landing"});
    FAIL() << "a hexa accepted spin_landing";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("motor_loss.mode"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("four rotors"), std::string::npos) << e.what();
  }
  try {
    spin_quad("quad_x", {"motor_loss.spin_rate_rad_s=30"});
    FAIL() << "a spin rate near the gyro's range was accepted";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("motor_loss.spin_rate_rad_s"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("gyro"), std::string::npos) << e.what();
  }
  EXPECT_THROW(spin_quad("quad_x", {"motor_loss.descent_rate_mps=9"}), config::ConfigError);
  EXPECT_THROW(spin_quad("quad_x", {"motor_loss.mode=sometimes"}), config::ConfigError);
}

class LandingLoopTest : public ::testing::Test {
 protected:
  config::Config config_ = spin_quad("quad_x", {"output.spool_up_s=0"});
  loop::ControlLoop loop_{config_, config::build_mixer(config_)};
  std::int64_t now_ = 1'000'000;
  std::int64_t utime_ = 1'700'000'000'000'000;

  const loop::CycleResult& cycle(bool armed, bool attitude, MotorMask failed) {
    now_ += 2500;
    utime_ += 2500;
    loop_.on_setpoint(loop::SetpointSample{utime_, 0.5, 0.0, armed}, now_, kWall);
    loop_.on_pid(loop::PidSample{utime_, 0.0, 0.0, 0.0}, now_, kWall);
    loop::MotorStatusSample status{utime_, 4, failed};
    loop_.on_motor_status(status, now_, kWall);
    if (attitude) {
      loop::AttitudeSample a;
      a.utime = utime_;
      a.velocity = {0.0, 0.0, 0.0};
      loop_.on_attitude(a, now_, kWall);
    }
    return loop_.cycle(now_);
  }
};

TEST_F(LandingLoopTest, OneFailedMotorWithAttitudeHandsTheOutputsToTheLanding) {
  ASSERT_TRUE(loop_.reads_attitude());
  cycle(false, true, 0);
  EXPECT_EQ(cycle(true, true, 0).landing.state, DescentPhase::kOff);
  const loop::CycleResult& r = cycle(true, true, 0b0001);
  EXPECT_EQ(r.landing.state, DescentPhase::kDescending);
  EXPECT_EQ(r.landing.motor, 0);
  EXPECT_TRUE(r.landing_changed);
  EXPECT_EQ(r.mix.output[0], config_.outputs[0].disarmed);
  for (int i = 1; i < 4; ++i) {
    EXPECT_GE(r.mix.output[i], config_.outputs[static_cast<std::size_t>(i)].min);
    EXPECT_LE(r.mix.output[i], config_.outputs[static_cast<std::size_t>(i)].max);
  }
}

TEST_F(LandingLoopTest, WithoutAFreshAttitudeItMixesAsBefore) {
  cycle(false, false, 0);
  cycle(true, false, 0);
  const loop::CycleResult& r = cycle(true, false, 0b0010);
  EXPECT_EQ(r.landing.state, DescentPhase::kNoAttitude);
  // The same outputs as the same vehicle without motor_loss.
  config::Config off = spin_quad("quad_x", {"output.spool_up_s=0", "motor_loss.mode=off"});
  Mixer mixer = config::build_mixer(off);
  MixerOutput expected;
  mixer.mix(AxisVector(0.0, 0.0, 0.0, 0.5), expected, 0.0, 0b0010);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(r.mix.output[i], expected.output[i], 1e-9);
}

TEST_F(LandingLoopTest, AStaleAttitudeLetsGoAndTwoFailedMotorsAreNotItsCase) {
  cycle(false, true, 0);
  cycle(true, true, 0);
  EXPECT_EQ(cycle(true, true, 0b0100).landing.state, DescentPhase::kDescending);
  const loop::CycleResult* r = nullptr;
  for (int k = 0; k < 40; ++k) r = &cycle(true, false, 0b0100);  // 100 ms without attitude
  EXPECT_EQ(r->landing.state, DescentPhase::kNoAttitude);
  EXPECT_EQ(cycle(true, true, 0b0100).landing.state, DescentPhase::kDescending);
  EXPECT_EQ(cycle(true, true, 0b0101).landing.state, DescentPhase::kOff);
}

TEST_F(LandingLoopTest, AFailsafeKeepsALandingGoingButNeverStartsOne) {
  cycle(false, true, 0);
  cycle(true, true, 0);
  // The controller's stream stops (only attitude and motor_status arrive).
  const auto quiet = [&](MotorMask failed) -> const loop::CycleResult& {
    now_ += 2500;
    utime_ += 2500;
    loop_.on_motor_status(loop::MotorStatusSample{utime_, 4, failed}, now_, kWall);
    loop::AttitudeSample a;
    a.utime = utime_;
    a.velocity = {0.0, 0.0, 1.0};
    loop_.on_attitude(a, now_, kWall);
    return loop_.cycle(now_);
  };
  const loop::CycleResult* r = nullptr;
  for (int k = 0; k < 60; ++k) r = &quiet(0);
  ASSERT_EQ(r->state, loop::LoopState::kFailsafe);
  r = &quiet(0b0001);  // a motor reported failed now: no landing, motors stay stopped
  EXPECT_NE(r->landing.state, DescentPhase::kDescending);
  EXPECT_EQ(r->mix.output[1], config_.outputs[1].disarmed);
  // Started while armed, a landing goes on through the failsafe.
  cycle(false, true, 0);
  cycle(true, true, 0);
  EXPECT_EQ(cycle(true, true, 0b0001).landing.state, DescentPhase::kDescending);
  for (int k = 0; k < 60; ++k) r = &quiet(0b0001);
  EXPECT_EQ(r->state, loop::LoopState::kFailsafe);
  EXPECT_EQ(r->landing.state, DescentPhase::kDescending);
  EXPECT_GT(r->mix.output[1], config_.outputs[1].disarmed);
}

TEST_F(LandingLoopTest, LandedDisarmsAndArmingAgainNeedsADisarmedSetpoint) {
  cycle(false, true, 0);
  cycle(true, true, 0);
  const loop::CycleResult* r = nullptr;
  // Velocity zero throughout: on the ground, so it lands within seconds.
  for (int k = 0; k < 2000; ++k) {
    r = &cycle(true, true, 0b1000);
    if (r->landing.state == DescentPhase::kLanded) break;
  }
  ASSERT_EQ(r->landing.state, DescentPhase::kLanded);
  EXPECT_EQ(r->state, loop::LoopState::kDisarmed);
  EXPECT_EQ(r->mix.output[1], config_.outputs[1].disarmed);
  // The setpoint still says armed: it stays disarmed.
  EXPECT_EQ(cycle(true, true, 0b1000).state, loop::LoopState::kDisarmed);
  cycle(false, true, 0b1000);
  EXPECT_EQ(cycle(true, true, 0b1000).state, loop::LoopState::kArmed);
}

}  // namespace
}  // namespace motormix::test
