// The simulator's own tests: the physics against conservation laws and
// equilibria, the sign of every axis through the real mixer and output
// stage, scenario and vehicle validation, lockstep determinism, and the
// closed-loop targets (any one motor of a hexa or octo stopping at hover).

#include "sim/bus/sim_log.hpp"
#include "sim/lockstep.hpp"
#include "sim/rigid_body.hpp"
#include "sim/scenario.hpp"
#include "sim/vehicle_model.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <sstream>

namespace motormix::sim {
namespace {

using test::source_path;

// Tolerances, named for what they bound.
constexpr double kFreeFallPositionM = 1e-9;     // RK4 is exact for constant acceleration
constexpr double kConservedRelative = 1e-7;     // momentum and energy after 10 s of free rotation
constexpr double kHoverDriftM = 0.005;          // altitude change in 1 s at the hover PWM
constexpr double kSignRateRadS = 1e-3;          // a rate that clearly has a sign
constexpr double kMotorOutAltitudeLossM = 1.0;  // issue targets for one motor stopping at hover
constexpr double kMotorOutAttitudeMaxDeg = 15.0;
// Regression bounds near today's figures (SIM.md: worst motor-out altitude
// loss 0.03 m; hover and motor-out altitude error at most 0.30 m, the team
// quad's climb overshoot), so that a change that flies worse but within the
// targets above is seen.
constexpr double kMotorOutAltitudeLossRegressionM = 0.1;
constexpr double kAltitudeErrorRegressionM = 0.5;
// Armed from shortly after the start to the end: the scenarios arm within
// their first half second.
constexpr double kArmedWithinS = 0.5;

// The run flew: armed nearly throughout, and climbed to the commanded
// altitude. A run that never armed or never left the ground scores no
// altitude loss and no attitude error, so every closed-loop check starts
// here.
void expect_flown(const SimResult& r, const std::string& what) {
  EXPECT_GE(r.armed_s, r.sim_seconds - kArmedWithinS) << what << ": armed " << r.armed_s << " s";
  EXPECT_TRUE(r.reached_altitude) << what << ": never reached the commanded altitude";
  EXPECT_LE(r.altitude_error_max_m, kAltitudeErrorRegressionM) << what;
}

config::Config load(const std::string& file, const std::vector<std::string>& overrides = {}) {
  return config::load_config_file(source_path("config/" + file), overrides);
}

config::Config preset(const std::string& name, const std::vector<std::string>& overrides = {}) {
  return config::load_config_text("geometry: {preset: " + name + "}\n", name, overrides);
}

// A vehicle placed in the air, level, at rest.
VehicleModel airborne(const config::Config& c, double altitude = 50.0) {
  VehicleModel v(c);
  BodyState b;
  b.position.z() = -altitude;
  v.set_body(b, false);
  return v;
}

TEST(RigidBody, FreeFallIsExact) {
  // No motors and no drag: z = z0 + g t^2 / 2, energy conserved.
  const config::Config c = preset("quad_x", {"vehicle.drag.linear=0", "vehicle.drag.rotational=0"});
  VehicleModel v = airborne(c, 100.0);
  const MotorVector off = MotorVector::Constant(4, 900.0);
  const DirectionVector dir{};
  const double dt = 1e-3;
  for (int k = 0; k < 2000; ++k) v.step(off, dir, 0, Environment{}, dt);
  const double t = 2.0;
  EXPECT_NEAR(v.body().position.z(), -100.0 + kGravity * t * t / 2, kFreeFallPositionM);
  EXPECT_NEAR(v.body().velocity.z(), kGravity * t, kFreeFallPositionM);
  // Per unit mass: kinetic plus potential (height is -z in NED).
  const double energy = 0.5 * v.body().velocity.squaredNorm() - kGravity * v.body().position.z();
  EXPECT_NEAR(energy, kGravity * 100.0, 1e-9 * kGravity * 100.0);
}

TEST(RigidBody, FreeRotationConservesMomentumAndEnergy) {
  // Torque-free rotation of an asymmetric body (the intermediate axis makes
  // it tumble): world angular momentum and rotational energy are conserved.
  MassProperties m;
  m.mass_kg = 1.0;
  m.inertia = {0.01, 0.02, 0.035};
  BodyState s;
  s.rates = {0.3, 4.0, 0.2};
  const auto none = [](const BodyState&) { return Wrench{}; };
  const auto momentum = [&](const BodyState& b) {
    return Eigen::Vector3d(b.attitude * m.inertia.cwiseProduct(b.rates));
  };
  const auto energy = [&](const BodyState& b) {
    return 0.5 * b.rates.dot(m.inertia.cwiseProduct(b.rates));
  };
  const Eigen::Vector3d l0 = momentum(s);
  const double e0 = energy(s);
  double max_tilt = 0;
  for (int k = 0; k < 10000; ++k) {
    s = rk4_step(s, m, none, 1e-3);
    max_tilt = std::max(max_tilt, tilt(s.attitude));
  }
  EXPECT_GT(max_tilt, 1.0) << "the body should tumble about its intermediate axis";
  EXPECT_LT((momentum(s) - l0).norm() / l0.norm(), kConservedRelative);
  EXPECT_LT(std::abs(energy(s) - e0) / e0, kConservedRelative);
  EXPECT_NEAR(s.attitude.norm(), 1.0, 1e-12);
}

// The PWM at which every rotor carries its share of the weight, from the
// physical ESC curve inverted by hand (not by the output stage).
double hover_pwm(const config::Config& c, double voltage) {
  const config::VehiclePhysics& p = c.vehicle_model;
  const double share =
      p.mass_kg * kGravity / static_cast<double>(p.rotors.size()) / p.rotors.front().max_thrust_n;
  const double v = voltage / p.battery.reference_v;
  const double e = p.thrust_expo;
  const double f = share / ((1 - e) * v + e * v * v);
  const double x = e > 0 ? (-(1 - e) + std::sqrt((1 - e) * (1 - e) + 4 * e * f)) / (2 * e) : f;
  return p.esc_min[0] + x * (p.esc_max[0] - p.esc_min[0]);
}

// The hover PWM depends on the voltage, which sags with the hover current:
// three seconds at the hover PWM of the voltage at the start of each
// (rotors and sag converge), each from 50 m up at rest. The vehicle is then
// 1 s into holding hover.
void settle_at_hover(const config::Config& c, VehicleModel& v) {
  for (int settle = 0; settle < 3; ++settle) {
    const MotorVector out =
        MotorVector::Constant(c.motors(), hover_pwm(c, v.battery().terminal_v()));
    BodyState start;
    start.position.z() = -50;
    v.set_body(start, false);
    for (int k = 0; k < 1000; ++k) v.step(out, DirectionVector{}, 0, Environment{}, 1e-3);
  }
}

TEST(VehicleModel, EqualCommandsAtTheHoverPwmHoldAltitude) {
  for (const char* name : {"quad_x", "hexa_x", "octo_x"}) {
    // A pack too large to discharge noticeably: its sag is then that of
    // the hover current alone, constant.
    const config::Config c = preset(name, {"vehicle.battery.capacity_mah=1e6"});
    VehicleModel v = airborne(c);
    settle_at_hover(c, v);
    EXPECT_NEAR(v.body().position.z(), -50.0, kHoverDriftM) << name;
    EXPECT_LT(v.body().rates.norm(), kSignRateRadS) << name;
  }
}

TEST(VehicleModel, HoverPowerMatchesAFlownReference) {
  // ArduPilot SITL's default multicopter model: 1.5 kg hovering on 22.7 A at
  // 12.14 V, 184 W per kg. The defaults here are sized to match it.
  constexpr double kReferenceWattsPerKg = 22.7 * 12.14 / 1.5;
  constexpr double kAgreement = 0.10;  // relative
  for (const char* name : {"quad_x", "hexa_x", "octo_x"}) {
    const config::Config c = preset(name, {"vehicle.battery.capacity_mah=1e6"});
    VehicleModel v = airborne(c);
    settle_at_hover(c, v);
    const double watts_per_kg =
        v.battery().terminal_v() * v.battery().current_a() / c.vehicle_model.mass_kg;
    EXPECT_NEAR(watts_per_kg, kReferenceWattsPerKg, kAgreement * kReferenceWattsPerKg) << name;
  }
}

// Hover outputs plus a step on one axis, through the configured mixer and
// output stage, then 50 ms of flight: the body rate that results.
Eigen::Vector3d rate_after_step(const config::Config& c, Axis axis, double step) {
  const Mixer mixer = config::build_mixer(c);
  VehicleModel v = airborne(c);
  AxisVector demand = AxisVector::Zero();
  demand[index(Axis::kThrust)] = 0.5;
  demand[index(axis)] += step;
  MixerOutput out;
  mixer.mix(demand, out);
  for (int k = 0; k < 50; ++k) v.step(out.output, out.direction, 0, Environment{}, 1e-3);
  return v.body().rates;
}

TEST(VehicleModel, EachAxisOfTheMixingMatrixTurnsTheBodyThatWay) {
  for (const char* file : {"quad_x.yaml", "hexa_x.yaml", "octo_x.yaml"}) {
    const config::Config c = load(file);
    for (Axis axis : {Axis::kRoll, Axis::kPitch, Axis::kYaw}) {
      const Eigen::Vector3d w = rate_after_step(c, axis, 0.2);
      const int a = index(axis);
      EXPECT_GT(w[a], kSignRateRadS) << file << " " << kAxisNames[static_cast<std::size_t>(a)];
      // and mostly on that axis
      for (int b = 0; b < 3; ++b) {
        if (b != a) {
          EXPECT_LT(std::abs(w[b]), 0.2 * std::abs(w[a])) << file << " axis " << a;
        }
      }
    }
  }
}

TEST(VehicleModel, TheTeamQuadsTableRollsRightAndPitchesNoseDown) {
  // The seed's sign table: positive roll lowers the right side (as every
  // preset), positive pitch raises the rear motors, so the nose goes down.
  const config::Config c = load("team_quad.yaml");
  EXPECT_GT(rate_after_step(c, Axis::kRoll, 0.2).x(), kSignRateRadS);
  EXPECT_LT(rate_after_step(c, Axis::kPitch, 0.2).y(), -kSignRateRadS);
  EXPECT_GT(rate_after_step(c, Axis::kYaw, 0.2).z(), kSignRateRadS);
}

TEST(VehicleModel, ACounterClockwiseRotorYawsTheBodyClockwise) {
  // quad_x m1 is front right, CCW: raising it alone yaws positive (nose
  // right), as Spin::kCcw says; m3 (front left, CW) the other way.
  const config::Config c = preset("quad_x");
  for (int motor : {0, 2}) {
    VehicleModel v = airborne(c);
    MotorVector out = MotorVector::Constant(4, 1500.0);
    out[motor] = 1700.0;
    for (int k = 0; k < 50; ++k) v.step(out, DirectionVector{}, 0, Environment{}, 1e-3);
    const double expected =
        c.vehicle_model.rotors[static_cast<std::size_t>(motor)].spin == Spin::kCcw ? 1 : -1;
    EXPECT_GT(expected * v.body().rates.z(), kSignRateRadS) << "motor " << motor + 1;
  }
}

TEST(VehicleModel, ResistsTheGroundAndCrashesOnAHardLanding) {
  const config::Config c = preset("quad_x");
  VehicleModel resting(c);
  const MotorVector off = MotorVector::Constant(4, 900.0);
  for (int k = 0; k < 1000; ++k) resting.step(off, DirectionVector{}, 0, Environment{}, 1e-3);
  EXPECT_EQ(resting.body().position.z(), 0.0);
  EXPECT_TRUE(resting.landed());
  EXPECT_FALSE(resting.crashed());
  VehicleModel dropped = airborne(c, 1.0);  // falls 1 m: 4.4 m/s at the ground
  for (int k = 0; k < 1000 && !dropped.crashed(); ++k)
    dropped.step(off, DirectionVector{}, 0, Environment{}, 1e-3);
  EXPECT_TRUE(dropped.crashed());
  EXPECT_NE(dropped.crash_reason().find("hit the ground"), std::string::npos);
  EXPECT_GE(dropped.body().position.z(), -1e-12) << "nothing falls through the floor";
}

TEST(VehicleModel, WheelsDriveForwardAndTurnAsTheirDirectionPinsSay) {
  const config::Config c = load("diff_drive.yaml");  // H-bridge: duty + direction pin
  const Mixer mixer = config::build_mixer(c);
  VehicleModel v(c);
  MixerOutput out;
  AxisVector forward = AxisVector::Zero();
  forward[index(Axis::kThrust)] = 0.5;
  mixer.mix(forward, out);
  for (int k = 0; k < 1000; ++k) v.step(out.output, out.direction, 0, Environment{}, 1e-3);
  EXPECT_GT(v.forward_speed(),
            0.4 * c.vehicle_model.wheels.radius_m * c.vehicle_model.wheels.max_speed_rad_s);
  EXPECT_GT(v.body().position.x(), 0.1);
  AxisVector back = -forward;
  mixer.mix(back, out);
  EXPECT_EQ(out.direction[0], -1);
  for (int k = 0; k < 3000; ++k) v.step(out.output, out.direction, 0, Environment{}, 1e-3);
  EXPECT_LT(v.forward_speed(), 0.0);
}

TEST(VehicleConfig, RejectsBadValuesNamingTheKey) {
  const auto message = [](const std::vector<std::string>& overrides) {
    try {
      preset("quad_x", overrides);
    } catch (const config::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(message({"vehicle.mass_kg=-1"}).find("vehicle.mass_kg"), std::string::npos);
  EXPECT_NE(message({"vehicle.battery.cells=0"}).find("vehicle.battery.cells"), std::string::npos);
  EXPECT_NE(message({"vehicle.wheel_radius_m=0.1"}).find("vehicle.wheel_radius_m"),
            std::string::npos);
  EXPECT_NE(message({"vehicle.inertia_kgm2=[1, 2]"}).find("vehicle.inertia_kgm2"),
            std::string::npos);
  EXPECT_NE(message({"vehicle.esc.thrust_expo=2"}).find("vehicle.esc.thrust_expo"),
            std::string::npos);
  EXPECT_NE(message({"vehicle.bogus=1"}).find("vehicle.bogus"), std::string::npos);
  // A table alone says nothing of where the rotors are.
  const config::Config table = config::load_config_text(
      "geometry:\n  mixing:\n    - [1, 1, 1, 1]\n    - [-1, -1, 1, 1]\n    - [1, -1, -1, 1]\n"
      "    - [-1, 1, -1, 1]\n",
      "table");
  EXPECT_NE(table.vehicle_model.incomplete.find("vehicle.rotors"), std::string::npos);
  EXPECT_THROW(VehicleModel{table}, std::invalid_argument);
  // Rotors given one by one, each with its own thrust and torque ratio.
  const config::Config given = config::load_config_text(
      "geometry:\n  mixing:\n    - [1, 1, 1, 1]\n    - [-1, -1, 1, 1]\n    - [1, -1, -1, 1]\n"
      "    - [-1, 1, -1, 1]\n"
      "vehicle:\n  rotors:\n"
      "    - {position: [-0.2, -0.2, 0], spin: ccw, max_thrust_n: 7}\n"
      "    - {position: [-0.2, 0.2, 0], spin: cw}\n"
      "    - {position: [0.2, -0.2, 0], spin: cw, torque_ratio_m: 0.02}\n"
      "    - {position: [0.2, 0.2, 0], spin: ccw}\n",
      "table with rotors");
  ASSERT_TRUE(given.vehicle_model.incomplete.empty());
  EXPECT_DOUBLE_EQ(given.vehicle_model.rotors[0].max_thrust_n, 7.0);
  EXPECT_DOUBLE_EQ(given.vehicle_model.rotors[2].torque_ratio_m, 0.02);
  EXPECT_DOUBLE_EQ(given.vehicle_model.rotors[1].torque_ratio_m, 0.016);
}

TEST(Scenario, ShippedOnesLoadAndBadOnesNameTheirKey) {
  for (const std::string& name : shipped_scenarios()) EXPECT_NO_THROW(load_scenario(name)) << name;
  EXPECT_GE(shipped_scenarios().size(), 7U);
  const auto message = [](const std::string& text) {
    try {
      parse_scenario(text, "test");
    } catch (const config::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(message("timeline: [{at: 1, rol_deg: 3}]").find("timeline[0].rol_deg"),
            std::string::npos);
  EXPECT_NE(message("duration_s: 5\ntimeline: [{at: 9}]").find("timeline[0].at"),
            std::string::npos);
  EXPECT_NE(message("timeline: [{at: 1, fail: 17}]").find("timeline[0].fail"), std::string::npos);
  EXPECT_NE(message("[1, 2").find("not valid YAML"), std::string::npos);
  EXPECT_THROW(load_scenario("/nonexistent/scenario.yaml"), config::ConfigError);
}

std::string file_bytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

std::string log_of(const config::Config& c, const Scenario& s, std::uint64_t seed,
                   const std::string& path) {
  {
    SimLogWriter log(path, c);
    SimOptions o;
    o.seed = seed;
    run_lockstep(c, config::build_mixer(c), s, o,
                 [&](const SimFrame& f) { log.write(f, *f.counters); });
  }
  return file_bytes(path);
}

TEST(Lockstep, TheSameSeedGivesTheSameBytes) {
  const config::Config c = load("hexa_x.yaml");
  Scenario s = load_scenario("gusts");
  s.duration_s = 6.0;
  const std::string dir = ::testing::TempDir();
  const std::string a = log_of(c, s, 7, dir + "/sim_a.lcmlog");
  const std::string b = log_of(c, s, 7, dir + "/sim_b.lcmlog");
  const std::string other = log_of(c, s, 8, dir + "/sim_c.lcmlog");
  EXPECT_GT(a.size(), 100000U);
  EXPECT_TRUE(a == b) << "same seed, different bytes";
  EXPECT_FALSE(a == other) << "the seed should change the sensor noise";
}

TEST(Lockstep, HoverHoldsAndArmsThroughTheRealLoop) {
  for (const char* file : {"quad_x.yaml", "team_quad.yaml", "hexa_x.yaml", "octo_x.yaml"}) {
    const config::Config c = load(file);
    const SimResult r = run_lockstep(c, config::build_mixer(c), load_scenario("hover"), {});
    EXPECT_FALSE(r.crashed) << file << ": " << r.crash_reason;
    EXPECT_LT(r.attitude_error_max_deg, 1.0) << file;
    EXPECT_LT(r.altitude_loss_m, 0.1) << file;
    EXPECT_EQ(r.failsafe_events, 0) << file;
    expect_flown(r, file);
  }
}

TEST(Lockstep, AQuadLosingAMotorIsReportedAsACrash) {
  // Without the spin landing: with it, the quad now comes down alive.
  const config::Config c = load("quad_x.yaml", {"motor_loss.mode=off"});
  const SimResult r = run_lockstep(c, config::build_mixer(c), load_scenario("motor_out"), {});
  EXPECT_TRUE(r.crashed);
  EXPECT_GT(r.crash_time_s, 6.0);
}

TEST(Lockstep, TheDriveFollowsSpeedAndTurnRate) {
  const config::Config c = load("diff_drive.yaml");
  Scenario s = load_scenario("drive");
  s.score_from_s = 2.0;  // the straight part, after the start
  s.score_to_s = 3.99;   // the spin starts at 4 s
  const SimResult r = run_lockstep(c, config::build_mixer(c), s, {});
  EXPECT_FALSE(r.crashed);
  EXPECT_LT(r.speed_error_rms_mps, 0.05);
  EXPECT_LT(r.yaw_rate_error_rms_dps, 2.0);
}

// Issue target: hexa X and octo X, optimal and prioritized, any one motor
// stopping at hover (reported after 100 ms): not crashed, altitude loss at
// most 1 m, roll/pitch error at most 15 degrees.
class MotorOut : public ::testing::TestWithParam<std::tuple<const char*, const char*>> {};

TEST_P(MotorOut, EveryMotorStopsAndTheVehicleStaysUp) {
  const auto [file, strategy] = GetParam();
  const config::Config c = load(file, {std::string("mixer.strategy=") + strategy});
  Scenario s = load_scenario("motor_out");
  s.timeline.clear();
  ASSERT_DOUBLE_EQ(s.failure_detection_s, 0.1);
  // Every motor; under the sanitizers (MOTORMIX_SIM_MOTOR_OUT=first_and_last)
  // the first and the last.
  const char* subset = std::getenv("MOTORMIX_SIM_MOTOR_OUT");
  const bool ends_only = subset != nullptr && std::string(subset) == "first_and_last";
  for (int m = 0; m < c.motors(); ++m) {
    if (ends_only && m != 0 && m != c.motors() - 1) continue;
    SimOptions o;
    o.failures.push_back({m, 6.0});
    const SimResult r = run_lockstep(c, config::build_mixer(c), s, o);
    EXPECT_FALSE(r.crashed) << file << " " << strategy << " m" << m + 1 << ": " << r.crash_reason;
    EXPECT_LE(r.altitude_loss_m, kMotorOutAltitudeLossM)
        << file << " " << strategy << " m" << m + 1;
    EXPECT_LE(r.attitude_error_max_deg, kMotorOutAttitudeMaxDeg)
        << file << " " << strategy << " m" << m + 1;
    EXPECT_LE(r.altitude_loss_m, kMotorOutAltitudeLossRegressionM)
        << file << " " << strategy << " m" << m + 1;
    expect_flown(r, std::string(file) + " " + strategy + " m" + std::to_string(m + 1));
  }
}

INSTANTIATE_TEST_SUITE_P(HexaAndOcto, MotorOut,
                         ::testing::Combine(::testing::Values("hexa_x.yaml", "octo_x.yaml"),
                                            ::testing::Values("optimal", "prioritized")));

}  // namespace
}  // namespace motormix::sim
