// Other stacks' formats, checked against the real frames: PX4's airframe
// parameters, ArduPilot's AP_MotorsMatrix factors, and a Paparazzi round trip
// of every preset.

#include "config/interop/paparazzi_import.hpp"

#include <motormix/angles.hpp>
#include "test_support.hpp"

#include <motormix/config/matrix_export.hpp>
#include <motormix/effectiveness/presets.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>

namespace motormix::test {
namespace {

// PX4's airframe files give positions to the millimetre.
constexpr double kPx4PositionM = 1e-3;
// Paparazzi coefficients are integers on a scale of 256: half a step.
constexpr double kPaparazziStep = 0.5 / 256.0;
// Factors compared after both sides are normalized.
constexpr double kFactor = 1e-6;

config::Config preset_config(const std::string& preset, const std::string& extra = "") {
  return config::load_config_text("geometry: {preset: " + preset + extra + "}\n", "test");
}

// "param set-default NAME VALUE" lines -> NAME -> VALUE.
std::map<std::string, double> px4_params(const std::string& text) {
  std::map<std::string, double> out;
  const std::regex line(R"(param set-default (\S+) (\S+))");
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) {
    std::smatch m;
    if (std::regex_match(l, m, line)) out[m[1]] = std::stod(m[2]);
  }
  return out;
}

struct Px4Rotor {
  double px, py, km;
};

void expect_px4(const std::string& preset, double arm, const std::vector<Px4Rotor>& reference) {
  std::ostringstream extra;
  extra << ", arm_length: " << arm;
  const auto params = px4_params(
      config::export_matrix(preset_config(preset, extra.str()), config::MatrixFormat::kPx4));
  EXPECT_EQ(params.at("CA_AIRFRAME"), 0.0);
  ASSERT_EQ(params.at("CA_ROTOR_COUNT"), static_cast<double>(reference.size()));
  for (std::size_t i = 0; i < reference.size(); ++i) {
    const std::string p = "CA_ROTOR" + std::to_string(i) + "_";
    SCOPED_TRACE(preset + " " + p);
    EXPECT_NEAR(params.at(p + "PX"), reference[i].px, kPx4PositionM);
    EXPECT_NEAR(params.at(p + "PY"), reference[i].py, kPx4PositionM);
    EXPECT_EQ(params.at(p + "PZ"), 0.0);
    EXPECT_EQ(params.at(p + "KM"), reference[i].km);
    EXPECT_EQ(params.at(p + "CT"), 6.5);  // PX4's default
  }
}

// PX4's generic quadrotor X airframe: rotors at (+-0.15, +-0.15), KM +0.05 for CCW.
TEST(Px4Export, QuadXMatchesPx4Airframe) {
  expect_px4(
      "quad_x", 0.15 * std::sqrt(2.0),
      {{0.15, 0.15, 0.05}, {-0.15, -0.15, 0.05}, {0.15, -0.15, -0.05}, {-0.15, 0.15, -0.05}});
}

// PX4's "Hex X with control allocation" airframe (arm 0.275 m).
TEST(Px4Export, HexaXMatchesPx4Airframe) {
  expect_px4("hexa_x", 0.275,
             {{0.0, 0.275, -0.05},
              {0.0, -0.275, 0.05},
              {0.238, -0.1375, -0.05},
              {-0.238, 0.1375, 0.05},
              {0.238, 0.1375, 0.05},
              {-0.238, -0.1375, -0.05}});
}

TEST(Px4Export, TiltedRotorsCarryTheirAxisAndTablesAreRefused) {
  const auto tilted = config::load_config_text(
      "geometry:\n  rotors:\n"
      "    - {position: [0.2, 0.2], spin: ccw}\n    - {position: [-0.2, -0.2], spin: ccw}\n"
      "    - {position: [0.2, -0.2], spin: cw, axis: [0, 0.2, -1]}\n"
      "    - {position: [-0.2, 0.2], spin: cw, thrust_coefficient: 2}\n",
      "test");
  const auto params = px4_params(config::export_matrix(tilted, config::MatrixFormat::kPx4));
  EXPECT_EQ(params.count("CA_ROTOR0_AX"), 0U);
  EXPECT_NEAR(params.at("CA_ROTOR2_AY"), 0.2 / std::sqrt(1.04), kFactor);
  EXPECT_NEAR(params.at("CA_ROTOR2_AZ"), -1.0 / std::sqrt(1.04), kFactor);
  EXPECT_EQ(params.at("CA_ROTOR3_CT"), 13.0);

  for (const char* table : {"team_quad", "differential_drive"}) {
    try {
      config::export_matrix(preset_config(table), config::MatrixFormat::kPx4);
      ADD_FAILURE() << table << " exported to px4";
    } catch (const config::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("needs a rotor geometry"), std::string::npos)
          << e.what();
    }
  }
}

struct ApMotor {
  double angle_deg;
  int yaw;  // AP_MOTORS_MATRIX_YAW_FACTOR_CCW = 1, CW = -1
  int testing_order;
};

// AP_MotorsMatrix: roll = cos(angle + 90), pitch = cos(angle), then each of
// roll, pitch and yaw scaled so its largest magnitude is 0.5
// (normalise_rpy_factors). Our export, normalized the same way, must agree.
void expect_ardupilot(const std::string& preset, const std::vector<ApMotor>& frame) {
  const std::string text =
      config::export_matrix(preset_config(preset), config::MatrixFormat::kArdupilot);
  const std::regex call(R"(MotorsMatrix:add_motor_raw\((\d+), (\S+), (\S+), (\S+), (\d+)\))");
  std::vector<std::array<double, 3>> ours;
  std::vector<int> ours_order;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) {
    std::smatch m;
    if (!std::regex_search(l, m, call)) continue;
    EXPECT_EQ(std::stoi(m[1]), static_cast<int>(ours.size()));
    ours.push_back({std::stod(m[2]), std::stod(m[3]), std::stod(m[4])});
    ours_order.push_back(std::stoi(m[5]));
  }
  ASSERT_EQ(ours.size(), frame.size());
  EXPECT_NE(text.find("MotorsMatrix:init(" + std::to_string(frame.size()) + ")"),
            std::string::npos);

  std::vector<std::array<double, 3>> ap;
  for (const ApMotor& m : frame) {
    const double a = m.angle_deg * kPi / 180.0;
    ap.push_back({std::cos(a + kPi / 2.0), std::cos(a), static_cast<double>(m.yaw)});
  }
  const auto normalise = [](std::vector<std::array<double, 3>>& f) {
    for (std::size_t axis = 0; axis < 3; ++axis) {
      double peak = 0.0;
      for (const auto& row : f) peak = std::max(peak, std::abs(row[axis]));
      for (auto& row : f) row[axis] = 0.5 * row[axis] / peak;
    }
  };
  normalise(ours);
  normalise(ap);
  for (std::size_t i = 0; i < frame.size(); ++i) {
    SCOPED_TRACE(preset + " motor " + std::to_string(i + 1));
    for (std::size_t axis = 0; axis < 3; ++axis) EXPECT_NEAR(ours[i][axis], ap[i][axis], kFactor);
    EXPECT_EQ(ours_order[i], frame[i].testing_order);
  }
}

// The tables of AP_MotorsMatrix::setup_quad_matrix and setup_hexa_matrix (X).
TEST(ArduPilotExport, QuadXMatchesApMotorsMatrix) {
  expect_ardupilot("quad_x", {{45, 1, 1}, {-135, 1, 3}, {-45, -1, 4}, {135, -1, 2}});
}

TEST(ArduPilotExport, HexaXMatchesApMotorsMatrix) {
  expect_ardupilot(
      "hexa_x", {{90, -1, 2}, {-90, 1, 5}, {-30, -1, 6}, {150, 1, 3}, {30, 1, 1}, {-150, -1, 4}});
}

TEST(ArduPilotExport, GroundVehiclesAreRefused) {
  EXPECT_THROW(
      config::export_matrix(preset_config("skid_steer_4"), config::MatrixFormat::kArdupilot),
      config::ConfigError);
}

// Every preset through `--format paparazzi` and back through
// `geometry: {paparazzi: ...}`: the same matrix to within the rounding of
// the 1/256 coefficients.
TEST(PaparazziImport, EveryPresetRoundTrips) {
  for (const std::string& name : preset_names()) {
    SCOPED_TRACE(name);
    const config::Config original = preset_config(name);
    const std::string xml = config::export_matrix(original, config::MatrixFormat::kPaparazzi);
    const MixingMatrix back = config::parse_paparazzi_mixing(xml, name + ".xml");
    ASSERT_EQ(back.rows(), original.mixing.rows());
    EXPECT_LE((back - original.mixing).cwiseAbs().maxCoeff(), kPaparazziStep);
  }
}

TEST(PaparazziImport, ReadsTheDocumentsAirframeSectionFromAFile) {
  // The H hexarotor of the pseudo-inverse mixing document, inside an airframe file.
  const std::string dir = ::testing::TempDir();
  {
    std::ofstream xml(dir + "/airframe.xml");
    xml << "<!DOCTYPE airframe SYSTEM \"../airframe.dtd\">\n<airframe name=\"h\">\n"
           "  <section name=\"IMU\" prefix=\"IMU_\"><define name=\"X\" value=\"1\"/></section>\n"
           "  <section name=\"MIXING\" prefix=\"MOTOR_MIXING_\">\n"
           "    <define name=\"TRIM_ROLL\" value=\"0\"/>\n"
           "    <define name=\"NB_MOTOR\" value=\"6\"/>\n"
           "    <define name=\"SCALE\" value=\"256\"/>\n"
           "    <define name=\"ROLL_COEF\"   value=\"{ -67,    67, -256,  256, -189,  189}\"/>\n"
           "    <define name=\"PITCH_COEF\"  value=\"{ -256, -256,    0,    0,  256,  256}\"/>\n"
           "    <define name=\"YAW_COEF\"    value=\"{ -154,  154,  256, -256, -115,  115}\"/>\n"
           "    <define name=\"THRUST_COEF\" value=\"{  256,  256,  256,  256,  256,  256}\"/>\n"
           "  </section>\n</airframe>\n";
  }
  std::ofstream(dir + "/vehicle.yaml") << "geometry: {paparazzi: airframe.xml}\n";
  const config::Config c = config::load_config_file(dir + "/vehicle.yaml");
  ASSERT_EQ(c.motors(), 6);
  EXPECT_NEAR(c.mixing(0, index(Axis::kRoll)), -67.0 / 256.0, kExact);
  EXPECT_NEAR(c.mixing(5, index(Axis::kYaw)), 115.0 / 256.0, kExact);
  EXPECT_NEAR(c.mixing(3, index(Axis::kThrust)), 1.0, kExact);
  // It matches the preset computed from the document's geometry.
  EXPECT_LE((c.mixing - preset_config("h_hexa").mixing).cwiseAbs().maxCoeff(), kPaparazziStep);
}

TEST(PaparazziImport, DamagedSectionsAreRefusedWithTheReason) {
  const auto refused = [](const std::string& body, const std::string& reason) {
    const std::string xml = "<section name=\"MIXING\">" + body + "</section>";
    try {
      config::parse_paparazzi_mixing(xml, "bad.xml");
      ADD_FAILURE() << "accepted: " << body;
    } catch (const config::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(reason), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("bad.xml"), std::string::npos) << e.what();
    }
  };
  const std::string rp =
      "<define name=\"ROLL_COEF\" value=\"{1,-1}\"/>"
      "<define name=\"PITCH_COEF\" value=\"{1,-1}\"/>";
  refused(rp, "YAW_COEF is missing");
  refused("<define name=\"TYPE\" value=\"QUAD_X\"/>", "TYPE 'QUAD_X' is not read");
  refused(rp + "<define name=\"YAW_COEF\" value=\"{1}\"/>", "YAW_COEF has 1 entries");
  refused(rp + "<define name=\"YAW_COEF\" value=\"{1, nan}\"/>", "YAW_COEF[1]");
  refused(rp + "<define name=\"YAW_COEF\" value=\"{1, 1e400}\"/>", "YAW_COEF[1]");
  refused(rp + "<define name=\"YAW_COEF\" value=\"{1, 2\"/>", "a list like");
  refused(rp + "<define name=\"YAW_COEF\" value=\"{1,1}\"/><define name=\"SCALE\" value=\"0\"/>",
          "SCALE");
  refused(rp + "<define name=\"YAW_COEF\" value=\"{1,1}\"/><define name=\"NB_MOTOR\" value=\"3\"/>",
          "NB_MOTOR");
  refused(rp + "<define name=\"YAW_COEF\" value=\"{1,1}\"/><define name=\"TRIM_YAW\" value=\"3\"/>",
          "TRIM_YAW");
  try {
    config::parse_paparazzi_mixing("<section name=\"MIXING\"><define", "bad.xml");
    ADD_FAILURE() << "accepted broken XML";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("not valid XML"), std::string::npos) << e.what();
  }
  EXPECT_THROW(config::parse_paparazzi_mixing("<airframe/>", "x.xml"), config::ConfigError);
  EXPECT_THROW(config::load_config_text("geometry: {paparazzi: /nonexistent/a.xml}\n", "t"),
               config::ConfigError);
}

}  // namespace
}  // namespace motormix::test
