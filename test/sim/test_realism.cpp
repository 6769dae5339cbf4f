// The simulator's realism (sim/realism.hpp), each piece against an
// independent statement of what it must do: the rotors' reaction torque
// conserves angular momentum, ground effect follows Cheeseman and Bennett,
// the gyro's low-pass has a Butterworth's magnitude and delay, late ESC
// telemetry arrives late and in order, and the switches and the model error
// read and apply as documented.

#include "sim/esc_telemetry_model.hpp"
#include "sim/imu.hpp"
#include "sim/lockstep.hpp"
#include "sim/realism.hpp"
#include "test_support.hpp"

#include <motormix/angles.hpp>
#include <motormix/config/build_mixer.hpp>
#include <motormix/config/load_config.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace motormix::sim {
namespace {

// Named tolerances.
constexpr double kMomentumRelTolerance = 1e-9;  // the reaction is exact by construction
constexpr double kFactorTolerance = 1e-12;
constexpr double kMagnitudeTolerance = 0.02;  // digital against analog, at f << fs
constexpr double kDelayShareTolerance = 0.10;
constexpr double kRoundOffRadS = 1e-12;

config::Config preset(const std::string& name, const std::vector<std::string>& overrides = {}) {
  return config::load_config_text("geometry: {preset: " + name + "}\n", name, overrides);
}

VehicleModel airborne(const config::Config& c, double altitude) {
  VehicleModel v(c);
  BodyState b;
  b.position.z() = -altitude;
  v.set_body(b, false);
  return v;
}

// The rotors' angular momentum about the body z axis, from their speeds.
double rotor_momentum_z(const VehicleModel& v) {
  const config::VehiclePhysics& p = v.physics();
  double h = 0.0;
  for (int i = 0; i < v.motors(); ++i) {
    const config::RotorPhysics& r = p.rotors[static_cast<std::size_t>(i)];
    const double speed = p.max_rotor_speed_rad_s * std::sqrt(std::max(v.motor_speed(i), 0.0));
    h += static_cast<double>(r.spin) * p.rotor_inertia_kgm2 * speed * r.axis.z();
  }
  return h;
}

TEST(Realism, SpeedingUpARotorTurnsTheBodyTheOtherWayWithMomentumConserved) {
  // No drag of any kind: the only yaw torque is the rotor's reaction, so
  // the body's and the rotors' momentum about z sum to what they started at.
  const config::Config c = preset(
      "quad_x", {"vehicle.torque_ratio_m=0", "vehicle.drag.rotational=0", "vehicle.drag.linear=0"});
  ASSERT_GT(c.vehicle_model.rotor_inertia_kgm2, 0.0);
  VehicleModel v = airborne(c, 100.0);
  MotorVector out = MotorVector::Constant(4, 1000.0);
  out[0] = 1800.0;  // one counter-clockwise rotor spinning up alone
  for (int k = 0; k < 200; ++k) v.step(out, DirectionVector{}, 0, Environment{}, 1e-3);
  const double body = c.vehicle_model.inertia_kgm2.z() * v.body().rates.z();
  const double rotors = rotor_momentum_z(v);
  ASSERT_GT(std::abs(rotors), 0.0);
  EXPECT_NEAR(body + rotors, 0.0, kMomentumRelTolerance * std::abs(rotors));
  // And without rotor inertia, nothing turns it.
  const config::Config none = preset(
      "quad_x",
      {"vehicle.torque_ratio_m=0", "vehicle.drag.rotational=0", "vehicle.rotor_inertia_kgm2=0"});
  VehicleModel still = airborne(none, 100.0);
  for (int k = 0; k < 200; ++k) still.step(out, DirectionVector{}, 0, Environment{}, 1e-3);
  EXPECT_NEAR(still.body().rates.z(), 0.0, kRoundOffRadS);
}

TEST(Realism, GroundEffectFollowsCheesemanAndBennettWithinOneDiameter) {
  const config::Config c = preset("quad_x");
  const double radius = c.vehicle_model.prop_diameter_m / 2;
  for (double z : {0.0, 0.25 * radius, radius, 1.5 * radius, 1.99 * radius, 2.01 * radius, 10.0}) {
    const VehicleModel v = airborne(c, z);
    const double h = std::max(z, radius / 2);  // the rotors sit at the centre's height
    const double q = radius / (4 * h);
    const double expected = z < 2 * radius ? 1.0 / (1.0 - q * q) : 1.0;
    for (int i = 0; i < v.motors(); ++i)
      EXPECT_NEAR(v.ground_effect(i), expected, kFactorTolerance);
  }
  const config::Config off = scenario_config(c, load_scenario("hover"), Realism::ideal());
  EXPECT_EQ(airborne(off, 0.0).ground_effect(0), 1.0);
}

// The steady amplitude ratio and the delay of a sine through the gyro filter.
void sine_response(double cutoff_hz, double f_hz, double fs_hz, double& ratio, double& delay_s) {
  GyroLowPass lp(cutoff_hz);
  const double dt = 1.0 / fs_hz;
  const int settle = static_cast<int>(5.0 * fs_hz);  // seconds of settling
  const int measure = static_cast<int>(std::ceil(20.0 / f_hz * fs_hz));
  double in_sin = 0, in_cos = 0, out_sin = 0, out_cos = 0;
  for (int k = 0; k < settle + measure; ++k) {
    const double phase = 2 * kPi * f_hz * k * dt;
    const double y = lp.filter(Eigen::Vector3d::Constant(std::sin(phase)), dt).x();
    if (k < settle) continue;
    in_sin += std::sin(phase) * std::sin(phase);
    in_cos += std::sin(phase) * std::cos(phase);
    out_sin += y * std::sin(phase);
    out_cos += y * std::cos(phase);
  }
  ratio = std::hypot(out_sin, out_cos) / std::hypot(in_sin, in_cos);
  delay_s = -std::atan2(out_cos, out_sin) / (2 * kPi * f_hz);
}

TEST(Realism, TheGyroLowPassHasAButterworthsMagnitudeAndDelay) {
  const double fc = 40.0, fs = 8000.0;
  for (double f : {5.0, 20.0, 40.0, 80.0}) {
    double ratio = 0, delay = 0;
    sine_response(fc, f, fs, ratio, delay);
    EXPECT_NEAR(ratio, 1.0 / std::sqrt(1.0 + std::pow(f / fc, 4)), kMagnitudeTolerance) << f;
  }
  // Well below the cutoff the delay is the analog filter's sqrt(2) / (2 pi fc).
  double ratio = 0, delay = 0;
  sine_response(fc, 2.0, fs, ratio, delay);
  const double expected = std::sqrt(2.0) / (2 * kPi * fc);
  EXPECT_NEAR(delay, expected, kDelayShareTolerance * expected);
  // A constant goes through unchanged from the first sample.
  GyroLowPass lp(fc);
  EXPECT_DOUBLE_EQ(lp.filter(Eigen::Vector3d::Constant(0.7), 1e-3).x(), 0.7);
  EXPECT_NEAR(lp.filter(Eigen::Vector3d::Constant(0.7), 1e-3).x(), 0.7, 1e-12);
}

TEST(Realism, TheImuShakesAtTheRotorsAndItsFilterTakesMostOfItAway) {
  // Hovering rotors, a body at rest: the realistic gyro reads vibration,
  // filtered; the idealized one only the bias.
  const config::Config c = preset("quad_x", {"vehicle.imu.bias_drift_dps=0"});
  VehicleModel v = airborne(c, 50.0);
  const MotorVector hover = MotorVector::Constant(4, 1500.0);
  for (int k = 0; k < 500; ++k) v.step(hover, DirectionVector{}, 0, Environment{}, 1e-3);
  Imu real(c.vehicle_model, 0.0, true, 7);
  Imu ideal(c.vehicle_model, 0.0, false, 7);
  double real_sq = 0, ideal_sq = 0;
  const int n = 4000;
  for (int k = 0; k < n; ++k) {
    v.step(hover, DirectionVector{}, 0, Environment{}, 2.5e-4);
    real.sample(v, 2.5e-4);
    ideal.sample(v, 2.5e-4);
    real_sq += (real.rates() - real.bias() - v.body().rates).squaredNorm();
    ideal_sq += (ideal.rates() - ideal.bias() - v.body().rates).squaredNorm();
  }
  const double real_rms_dps = std::sqrt(real_sq / n) / kRadPerDeg;
  EXPECT_NEAR(std::sqrt(ideal_sq / n), 0.0, kRoundOffRadS);
  // Four rotors of vibration_dps each at their hover share, before the
  // filter: the filter leaves a fraction of it.
  const double unfiltered_bound_dps = 4 * c.vehicle_model.imu.vibration_dps;
  EXPECT_GT(real_rms_dps, 0.0);
  EXPECT_LT(real_rms_dps, 0.5 * unfiltered_bound_dps);
}

TEST(Realism, LateEscTelemetryArrivesLateAndInOrder) {
  const config::Config c = preset("quad_x");
  VehicleModel v = airborne(c, 50.0);
  const MotorHealth healthy = MotorHealth::healthy(4);
  EscTelemetryModel late(4, 3, true), prompt(4, 3, false);
  int late_count = 0, prompt_count = 0;
  double first_late = -1, first_prompt = -1;
  for (int k = 0; k < 2000; ++k) {
    const double t = k * 1e-3;
    const int l = late.sample(t, k, v, healthy).count;
    const int p = prompt.sample(t, k, v, healthy).count;
    if (l > 0 && first_late < 0) first_late = t;
    if (p > 0 && first_prompt < 0) first_prompt = t;
    late_count += l;
    prompt_count += p;
  }
  EXPECT_GE(first_late, first_prompt + kEscLatencyS - 1e-9);
  // The same frames (one seed: the same rates, phases and losses, less
  // what is still on its way at the end).
  EXPECT_LE(late_count, prompt_count);
  EXPECT_GE(late_count, prompt_count - 4 * 4);
}

TEST(Realism, SwitchesAndModelErrorReadAsDocumented) {
  Realism r;
  EXPECT_EQ(apply_switches(r, "imu=off,ground_effect=off"), std::nullopt);
  EXPECT_FALSE(r.imu);
  EXPECT_FALSE(r.ground_effect);
  EXPECT_TRUE(r.rotor_momentum);
  EXPECT_NE(apply_switches(r, "gyro=off")->find("unknown piece 'gyro'"), std::string::npos);
  EXPECT_NE(apply_switches(r, "imu=maybe")->find("on or off"), std::string::npos);
  EXPECT_NE(apply_switches(r, "imu")->find("KEY=VALUE"), std::string::npos);
  const Realism ideal = Realism::ideal();
  for (const auto& piece : kRealismPieceNames) EXPECT_FALSE(ideal[piece.value]) << piece.name;

  ModelError e;
  EXPECT_EQ(parse_model_error(e, "mass=1.3,drag=0.7"), std::nullopt);
  EXPECT_DOUBLE_EQ(e.mass, 1.3);
  EXPECT_DOUBLE_EQ(e.drag, 0.7);
  EXPECT_NE(parse_model_error(e, "mass=20")->find("0.1 to 10"), std::string::npos);
  EXPECT_NE(parse_model_error(e, "weight=1")->find("unknown factor"), std::string::npos);

  const config::Config c = preset("quad_x");
  const config::Config t = truth_config(c, e);
  EXPECT_DOUBLE_EQ(t.vehicle_model.mass_kg, 1.3 * c.vehicle_model.mass_kg);
  EXPECT_DOUBLE_EQ(t.vehicle_model.drag_rotational_nm_per_radps,
                   0.7 * c.vehicle_model.drag_rotational_nm_per_radps);
  EXPECT_EQ(t.vehicle_model.inertia_kgm2, c.vehicle_model.inertia_kgm2);
}

TEST(Realism, PiecesSwitchedOffAreGoneFromWhatMotormixSeesToo) {
  const config::Config c = preset("quad_x", {"failure_detection.enabled=true"});
  ASSERT_TRUE(c.motor_loss && c.failure_detection);
  ASSERT_GT(c.motor_loss->model.rotor_inertia_kgm2, 0.0);
  const config::Config flown = scenario_config(c, load_scenario("hover"), Realism::ideal());
  EXPECT_EQ(flown.vehicle_model.rotor_inertia_kgm2, 0.0);
  ASSERT_TRUE(flown.motor_loss.has_value());
  EXPECT_EQ(flown.motor_loss->model.rotor_inertia_kgm2, 0.0);
  EXPECT_EQ(flown.vehicle_model.time_constant_down_s, flown.vehicle_model.time_constant_up_s);
  EXPECT_EQ(flown.failure_detection->detector.time_constant_down_s,
            flown.vehicle_model.time_constant_up_s);
  EXPECT_EQ(flown.failure_detection->detector.momentum_per_speed.norm(), 0.0);
}

TEST(Realism, AVehicleHeavierThanItsConfigurationStillHovers) {
  // The controller integrates the missing thrust away: 30 % more mass and
  // inertia, 30 % less drag, motors 30 % slower than configured.
  const config::Config c = config::load_config_file(test::source_path("config/quad_x.yaml"));
  SimOptions o;
  ASSERT_EQ(parse_model_error(o.realism.truth, "mass=1.3,inertia=1.3,drag=0.7,time_constant=1.3"),
            std::nullopt);
  const SimResult r = run_lockstep(c, config::build_mixer(c), load_scenario("hover"), o);
  EXPECT_FALSE(r.crashed) << r.crash_reason;
  EXPECT_TRUE(r.reached_altitude);
  EXPECT_LT(r.altitude_loss_m, 1.0);
}

}  // namespace
}  // namespace motormix::sim
