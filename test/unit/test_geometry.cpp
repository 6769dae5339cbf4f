// Geometry -> effectiveness -> mixing matrix, against the documents: the
// pseudo-inverse H-hexa example, the quad + and X tables, the wheel formulas;
// and properties over seeded random geometries.

#include <motormix/config/matrix_export.hpp>
#include "test_support.hpp"

#include <motormix/effectiveness/effectiveness.hpp>
#include <motormix/effectiveness/mixing_matrix.hpp>
#include <motormix/effectiveness/presets.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <random>

namespace motormix::test {
namespace {

using ::testing::HasSubstr;

// Derived matrices against hand-written tables: pinv and normalization
// rounding only.
constexpr double kDerived = 1e-12;

config::Config load(const std::string& yaml, const std::vector<std::string>& overrides = {}) {
  return config::load_config_text(yaml, "test.yaml", overrides);
}

MixingMatrix table(std::initializer_list<std::array<double, 4>> rows) {
  MixingMatrix m(static_cast<Eigen::Index>(rows.size()), kNumAxes);
  Eigen::Index i = 0;
  for (const auto& r : rows) {
    for (int a = 0; a < kNumAxes; ++a) m(i, a) = r[static_cast<std::size_t>(a)];
    ++i;
  }
  return m;
}

void expect_matrix_near(const MixingMatrix& got, const MixingMatrix& want, double tol) {
  ASSERT_EQ(got.rows(), want.rows());
  for (Eigen::Index i = 0; i < got.rows(); ++i) {
    for (int a = 0; a < kNumAxes; ++a) {
      EXPECT_NEAR(got(i, a), want(i, a), tol) << "motor " << i << " axis " << kAxisNames[a];
    }
  }
}

// The H hexarotor of the pseudo-inverse document: effectiveness rows as
// printed, expected coefficients as printed.
const std::vector<std::vector<long>> kSeed001Coefficients = {
    {-67, -256, -154, 256}, {67, -256, 154, 256},   {-256, 0, 256, 256},
    {256, 0, -256, 256},    {-189, 256, -115, 256}, {189, 256, 115, 256}};

TEST(Seed001, EffectivenessRowsGiveThePublishedCoefficients) {
  const auto c = load(
      "geometry:\n  effectiveness:\n"
      "    roll:  [-0.17,  0.17, -0.25,  0.25, -0.33,  0.33]\n"
      "    pitch: [-0.35, -0.35,  0.0,   0.0,   0.35,  0.35]\n"
      "    yaw:   [-0.1,   0.1,   0.1,  -0.1,  -0.1,   0.1]\n");
  EXPECT_EQ(config::scaled_coefficients(c.mixing, 256.0), kSeed001Coefficients);
  const std::string section = config::export_matrix(c, config::MatrixFormat::kPaparazzi);
  EXPECT_THAT(section, HasSubstr("<define name=\"NB_MOTOR\" value=\"6\"/>"));
  EXPECT_THAT(section, HasSubstr("<define name=\"SCALE\" value=\"256\"/>"));
  EXPECT_THAT(section, HasSubstr("value=\"{  -67,   67, -256,  256, -189,  189}\""));
  EXPECT_THAT(section, HasSubstr("value=\"{ -154,  154,  256, -256, -115,  115}\""));
  EXPECT_THAT(section, HasSubstr("value=\"{  256,  256,  256,  256,  256,  256}\""));
}

TEST(Seed001, HHexaPresetIsTheSameFrame) {
  EXPECT_EQ(config::scaled_coefficients(load("geometry: {preset: h_hexa}\n").mixing, 256.0),
            kSeed001Coefficients);
}

// The quad tables: 71 % on the X frame becomes 100 % after normalization.
TEST(Seed003, QuadXTable) {
  expect_matrix_near(load("geometry: {preset: quad_x}\n").mixing,
                     table({{-1, 1, 1, 1},      // 0 front right, CCW
                            {1, -1, 1, 1},      // 1 rear left, CCW
                            {1, 1, -1, 1},      // 2 front left, CW
                            {-1, -1, -1, 1}}),  // 3 rear right, CW
                     kDerived);
}

TEST(Seed003, QuadXBeforeNormalizationIs71Percent) {
  const auto c = load("geometry: {preset: quad_x, normalization: none}\n");
  const double roll = c.mixing(0, index(Axis::kRoll));
  const double pitch = c.mixing(0, index(Axis::kPitch));
  EXPECT_NEAR(std::abs(roll) / std::hypot(roll, pitch), std::sqrt(0.5), kDerived);
}

TEST(Seed003, QuadPlusTable) {
  expect_matrix_near(load("geometry: {preset: quad_plus}\n").mixing,
                     table({{-1, 0, 1, 1},     // 0 right, CCW
                            {1, 0, 1, 1},      // 1 left, CCW
                            {0, 1, -1, 1},     // 2 front, CW
                            {0, -1, -1, 1}}),  // 3 rear, CW
                     kDerived);
}

TEST(Seed000Preset, TeamQuadPresetIsTheSignTable) {
  expect_matrix_near(load("geometry: {preset: team_quad}\n").mixing,
                     table({{1, -1, 1, 1}, {-1, -1, -1, 1}, {1, 1, -1, 1}, {-1, 1, 1, 1}}), 0.0);
}

// Wheel speeds from (v, w): left = (2v - L w) / 2r, right = (2v + L w) / 2r.
TEST(Seed002, DifferentialDriveMatchesTheWheelFormulas) {
  const auto c = load(
      "geometry: {differential_drive: {wheel_radius: 5, track_width: 10, max_wheel_speed: 1}}\n");
  ASSERT_TRUE(c.wheel_base);
  EXPECT_NEAR(c.wheel_base->max_forward_speed(), 5.0, kDerived);  // r * w_max
  EXPECT_NEAR(c.wheel_base->max_turn_rate(), 1.0, kDerived);      // 2 r w_max / L
  expect_matrix_near(c.mixing, table({{0, 0, -1, 1}, {0, 0, 1, 1}}), kDerived);
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> speed(-5.0, 5.0);
  std::uniform_real_distribution<double> turn(-1.0, 1.0);
  for (int k = 0; k < 1000; ++k) {
    const double v = speed(rng);
    const double w = turn(rng);
    AxisVector demand(0, 0, w / c.wheel_base->max_turn_rate(),
                      v / c.wheel_base->max_forward_speed());
    const Eigen::VectorXd wheels = c.mixing * demand * c.wheel_base->max_wheel_speed;
    EXPECT_NEAR(wheels[0], (2 * v - 10 * w) / (2 * 5), kDerived);
    EXPECT_NEAR(wheels[1], (2 * v + 10 * w) / (2 * 5), kDerived);
  }
  // The document's saturating example before desaturation: move(1.0, 0.9).
  const Eigen::VectorXd raw = c.mixing * AxisVector(0, 0, 0.9, 1.0 / 5.0);
  EXPECT_NEAR(raw[0], -0.7, kDerived);
  EXPECT_NEAR(raw[1], 1.1, kDerived);
}

TEST(Geometry, SkidSteerSidesAreTheDifferentialDrive) {
  const auto c = load("geometry: {skid_steer: {wheels_per_side: 3}}\n");
  EXPECT_EQ(c.motor_names(), (std::vector<std::string>{"FL", "FR", "ML", "MR", "RL", "RR"}));
  for (int i = 0; i < 6; ++i) {
    EXPECT_NEAR(c.mixing(i, index(Axis::kYaw)), i % 2 == 0 ? -1.0 : 1.0, kDerived);
    EXPECT_NEAR(c.mixing(i, index(Axis::kThrust)), 1.0, kDerived);
  }
  EXPECT_EQ(c.thrust_range(), ThrustRange::kBipolar);
}

TEST(Geometry, RankDeficientGeometriesAreRejectedNamingTheAxes) {
  const auto error_of = [](const std::string& yaml) {
    try {
      load(yaml);
    } catch (const config::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  // All rotors on one line: no roll.
  EXPECT_THAT(error_of("geometry: {rotors: [{position: [1, 0], spin: cw}, {position: [-1, 0], "
                       "spin: ccw}, {position: [0.5, 0], spin: ccw}, {position: [-0.5, 0], spin: "
                       "cw}]}\n"),
              HasSubstr("cannot command roll"));
  // All spinning the same way: yaw and thrust cannot be told apart.
  EXPECT_THAT(error_of("geometry: {preset: quad_x, normalization: none}\n"),
              HasSubstr("(accepted)"));
  EXPECT_THAT(error_of("geometry: {rotors: [{position: [1, 1], spin: cw}, {position: [-1, -1], "
                       "spin: cw}, {position: [1, -1], spin: cw}, {position: [-1, 1], spin: "
                       "cw}]}\n"),
              HasSubstr("cannot command yaw, thrust"));
  EXPECT_THAT(error_of("geometry: {effectiveness: {roll: [1, -1], pitch: [0, 0], yaw: [1, -1]}}\n"),
              HasSubstr("rank"));
}

TEST(Geometry, PresetOptions) {
  const auto base = load("geometry: {preset: hexa_x}\n");
  const auto reversed = load("geometry: {preset: hexa_x, reverse_spin: true}\n");
  const auto longer = load("geometry: {preset: hexa_x, arm_length: 0.6}\n");
  const auto reordered = load("geometry: {preset: hexa_x, motor_order: [6, 5, 4, 3, 2, 1]}\n");
  for (int i = 0; i < 6; ++i) {
    EXPECT_NEAR(reversed.mixing(i, index(Axis::kYaw)), -base.mixing(i, index(Axis::kYaw)),
                kDerived);
    EXPECT_NEAR(reversed.mixing(i, index(Axis::kRoll)), base.mixing(i, index(Axis::kRoll)),
                kDerived);
    for (int a = 0; a < kNumAxes; ++a) {
      EXPECT_NEAR(longer.mixing(i, a), base.mixing(i, a), kDerived);
      EXPECT_NEAR(reordered.mixing(i, a), base.mixing(5 - i, a), kDerived);
    }
  }
  EXPECT_EQ(reordered.motor_names()[0], "m6");
  EXPECT_THROW(load("geometry: {preset: hexa_x, motor_order: [1, 1, 2, 3, 4, 5]}\n"),
               config::ConfigError);
  EXPECT_THROW(load("geometry: {rotors: [{position: [1, 0], spin: cw}], reverse_spin: true}\n"),
               config::ConfigError);
}

TEST(Geometry, Px4NormalizationSharesRollAndPitch) {
  const auto c = load("geometry: {preset: quad_x, normalization: px4}\n");
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(std::abs(c.mixing(i, index(Axis::kRoll))), std::sqrt(0.5), kDerived);
    EXPECT_NEAR(std::abs(c.mixing(i, index(Axis::kPitch))), std::sqrt(0.5), kDerived);
    EXPECT_NEAR(std::abs(c.mixing(i, index(Axis::kYaw))), 1.0, kDerived);
    EXPECT_NEAR(c.mixing(i, index(Axis::kThrust)), 1.0, kDerived);
  }
}

TEST(Geometry, EveryPresetIsFullRankAndThrustNormalized) {
  for (const std::string& name : preset_names()) {
    SCOPED_TRACE(name);
    const auto c = load("geometry: {preset: " + name + "}\n");
    const AxisMask controlled = c.geometry.controlled;
    EXPECT_EQ(controlled_axes(c.mixing), controlled);
    for (int i = 0; i < c.motors(); ++i)
      EXPECT_NEAR(c.mixing(i, index(Axis::kThrust)), 1.0, kDerived);
    // Authority is positive on every controlled axis.
    const AxisVector authority = config::authority_of(c);
    for (int a = 0; a < kNumAxes; ++a) {
      if ((controlled >> a) & 1U) {
        EXPECT_GT(authority[a], 0.1) << kAxisNames[a];
      }
    }
  }
}

TEST(Geometry, YamlExportFreezesTheMatrixExactly) {
  for (const char* name : {"hexa_x", "y6", "octo_coax_x8", "h_hexa"}) {
    const auto c = load("geometry: {preset: " + std::string(name) + "}\n");
    const auto frozen = load(config::export_matrix(c, config::MatrixFormat::kYaml));
    EXPECT_EQ(frozen.mixing, c.mixing) << name;
    EXPECT_EQ(frozen.motor_names(), c.motor_names());
  }
}

// Over random geometries: the physical effectiveness times the mixing matrix
// is diagonal and positive (each axis demand produces that axis only), and
// the normalized effectiveness inverts the mixing matrix.
TEST(GeometryProperty, MixingDecouplesTheAxesOfRandomGeometries) {
  std::mt19937_64 rng(4242);
  std::uniform_real_distribution<double> coord(-1.0, 1.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<int> count(4, 12);
  int checked = 0;
  for (int k = 0; k < 2000; ++k) {
    std::vector<Rotor> rotors(static_cast<std::size_t>(count(rng)));
    for (Rotor& r : rotors) {
      r.position = {coord(rng), coord(rng), 0.1 * coord(rng)};
      r.axis = {0.2 * coord(rng), 0.2 * coord(rng), -1.0};
      r.spin = unit(rng) < 0.5 ? Spin::kCw : Spin::kCcw;
      r.thrust_coefficient = 0.5 + unit(rng);
      r.torque_ratio = 0.01 + 0.1 * unit(rng);
    }
    const EffectivenessMatrix e = rotor_effectiveness(rotors);
    const MixingDerivation d = derive_mixing(e, kAllAxes, Normalization::kAxisMax);
    if (!d.ok()) continue;
    ++checked;
    const Eigen::Matrix4d produced = e * d.mixing;
    for (int a = 0; a < kNumAxes; ++a) {
      for (int b = 0; b < kNumAxes; ++b) {
        if (a == b) {
          ASSERT_GT(produced(a, a), 0.0);
        } else {
          ASSERT_NEAR(produced(a, b), 0.0, 1e-9 * produced.cwiseAbs().maxCoeff()) << k;
        }
      }
    }
    const Eigen::Matrix4d identity = effectiveness_of(d.mixing) * d.mixing;
    ASSERT_TRUE(identity.isApprox(Eigen::Matrix4d::Identity(), 1e-9)) << k;
    // Any demand whose commands stay within limits is reproduced exactly.
    AxisVector demand(coord(rng), coord(rng), coord(rng), unit(rng));
    demand *= 0.1;
    const Eigen::VectorXd u = d.mixing * demand;
    const AxisVector back = effectiveness_of(d.mixing) * u;
    ASSERT_TRUE(back.isApprox(demand, 1e-9)) << k;
  }
  EXPECT_GT(checked, 1500);
}

}  // namespace
}  // namespace motormix::test
