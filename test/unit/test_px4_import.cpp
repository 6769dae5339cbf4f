// `motormix import px4-params`: a PX4 flight log's parameters (the shared
// SITL log) and a hand-written .params file become configurations that
// load, with every rotor, spin, output range and strategy setting where
// PX4 had it; what is not mapped is named; damaged input is refused with
// the file and the reason.

#include "test_support.hpp"

#include <motormix/config/build_mixer.hpp>
#include <motormix/config/load_config.hpp>
#include <motormix/config/px4_import.hpp>
#include <motormix/config/ulog.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <map>
#include <stdexcept>
#include <string>

#include <unistd.h>

namespace motormix::test {
namespace {

constexpr double kCopiedExactly = 1e-6;  // values written with 7 significant digits
// motormix's commands against PX4's own actuator_motors on the shared flight
// (issue 50: fails below a 1e-5 match; measured by hand at 1e-7, with the
// geometry at full precision: the import writes seven digits).
constexpr double kPx4MatchTolerance = 1e-5;
constexpr std::size_t kPx4MatchedSamplesMin = 300;  // of 313 logged

bool lists(const std::vector<std::string>& v, const std::string& text) {
  return std::any_of(v.begin(), v.end(),
                     [&](const std::string& s) { return s.find(text) != std::string::npos; });
}

TEST(Px4Import, TheSharedFlightLogsAirframe) {
  const std::string path = source_path("test/data/px4/sample_px4_events.ulg");
  const config::Px4Parameters p = config::read_px4_parameters(path);
  EXPECT_EQ(p.format, "ulog");
  ASSERT_EQ(p.values.count("CA_ROTOR_COUNT"), 1U);
  EXPECT_EQ(p.values.at("CA_ROTOR_COUNT"), 4.0);
  const config::Px4Import imported = config::import_px4(p, path);
  const config::Config c = config::load_config_text(imported.yaml, "imported");
  ASSERT_EQ(c.motors(), 4);
  ASSERT_EQ(c.geometry.rotors.size(), 4U);
  for (int i = 0; i < 4; ++i) {
    SCOPED_TRACE("rotor " + std::to_string(i));
    const std::string k = "CA_ROTOR" + std::to_string(i) + "_";
    const Rotor& r = c.geometry.rotors[static_cast<std::size_t>(i)];
    EXPECT_NEAR(r.position.x(), p.values.at(k + "PX"), kCopiedExactly);
    EXPECT_NEAR(r.position.y(), p.values.at(k + "PY"), kCopiedExactly);
    const double km = p.values.count(k + "KM") ? p.values.at(k + "KM") : 0.05;
    EXPECT_EQ(r.spin, km >= 0.0 ? Spin::kCcw : Spin::kCw);
    EXPECT_NEAR(r.torque_ratio, std::abs(km), kCopiedExactly);
  }
  // Unequal arms: the Iris shape, not a square.
  EXPECT_GT(std::abs(std::abs(c.geometry.rotors[0].position.x()) -
                     std::abs(c.geometry.rotors[0].position.y())),
            0.05);
  EXPECT_EQ(c.strategy, config::Strategy::kPrioritized);
  EXPECT_EQ(named_airmode(c.airmode), Airmode::kOff);  // MC_AIRMODE 0
  EXPECT_NE(imported.yaml.find("normalization: px4"), std::string::npos) << imported.yaml;
}

// The imported configuration mixes the flight's logged torque and thrust
// setpoints into PX4's own motor commands, sample by sample (paired by the
// sample time the control allocator carries from its inputs).
TEST(Px4Import, MotormixMixesTheSharedFlightAsPx4Did) {
  const std::string path = source_path("test/data/px4/sample_px4_events.ulg");
  const config::Ulog log = config::Ulog::read(path);
  const config::Px4Parameters p = config::read_px4_parameters(path);
  const config::Config c = config::load_config_text(config::import_px4(p, path).yaml, "imported");
  const Mixer mixer = config::build_mixer(c);
  const std::vector<std::string> xyz{"timestamp_sample", "xyz[0]", "xyz[1]", "xyz[2]"};
  std::map<double, std::vector<double>> torque, thrust;
  for (auto& row : log.samples("vehicle_torque_setpoint", xyz)) torque[row[0]] = row;
  for (auto& row : log.samples("vehicle_thrust_setpoint", xyz)) thrust[row[0]] = row;
  const auto motors = log.samples("actuator_motors", {"timestamp_sample", "control[0]",
                                                      "control[1]", "control[2]", "control[3]"});
  std::size_t compared = 0;
  double worst = 0.0;
  MixerOutput out;
  for (const auto& m : motors) {
    const auto t = torque.find(m[0]);
    const auto f = thrust.find(m[0]);
    if (t == torque.end() || f == thrust.end()) continue;
    if (std::any_of(m.begin() + 1, m.end(), [](double v) { return std::isnan(v); })) continue;
    mixer.mix(AxisVector(t->second[1], t->second[2], t->second[3], -f->second[3]), out);
    for (int i = 0; i < 4; ++i)
      worst = std::max(worst, std::abs(out.command[i] - m[static_cast<std::size_t>(i) + 1]));
    ++compared;
  }
  std::printf("%zu of %zu actuator_motors samples compared; largest difference %.3g\n", compared,
              motors.size(), worst);
  // A nested field: each ESC's report inside esc_status.
  const auto rpm = log.samples("esc_status", {"esc_count", "esc[0].esc_rpm", "esc[3].esc_rpm"});
  ASSERT_FALSE(rpm.empty());
  EXPECT_EQ(rpm.size(), 126U);
  EXPECT_EQ(rpm.back()[0], 6.0);  // as logged (the SITL's ESC count), decoded independently too
  EXPECT_THROW(log.samples("esc_status", {"esc[0].no_such_field"}), std::runtime_error);
  EXPECT_THROW(log.samples("no_such_topic", {"timestamp"}), std::runtime_error);
  EXPECT_GE(compared, kPx4MatchedSamplesMin);
  EXPECT_LE(worst, kPx4MatchTolerance);
}

TEST(Px4Import, AParamsFileWithMotorsOnOtherOutputs) {
  const std::string path = source_path("test/data/px4/hexa_outputs.params");
  const config::Px4Parameters p = config::read_px4_parameters(path);
  EXPECT_EQ(p.format, "params");
  const config::Px4Import imported = config::import_px4(p, path);
  const config::Config c = config::load_config_text(imported.yaml, "imported");
  ASSERT_EQ(c.motors(), 6);
  EXPECT_EQ(c.geometry.rotors[0].spin, Spin::kCw);  // KM -0.05
  EXPECT_EQ(c.geometry.rotors[1].spin, Spin::kCcw);
  EXPECT_NEAR(c.geometry.rotors[0].position.y(), 0.25, kCopiedExactly);
  EXPECT_NEAR(c.geometry.rotors[5].thrust_coefficient, 6.0, kCopiedExactly);
  EXPECT_NEAR(c.geometry.rotors[4].thrust_coefficient, 6.5, kCopiedExactly);  // PX4's default
  EXPECT_EQ(named_airmode(c.airmode), Airmode::kRollPitch);                   // MC_AIRMODE 1
  // Motor 1 is on output 2 (FUNC2 = 101), motor 2 on output 1.
  EXPECT_EQ(c.outputs[0].min, 1050.0);
  EXPECT_EQ(c.outputs[0].max, 1950.0);
  EXPECT_EQ(c.outputs[0].disarmed, 950.0);
  EXPECT_EQ(c.outputs[1].min, 1100.0);
  EXPECT_EQ(c.outputs[1].max, 2000.0);
  EXPECT_EQ(c.outputs[1].disarmed, 900.0);
  EXPECT_EQ(c.outputs[5].min, 1000.0);
  EXPECT_NEAR(c.outputs[0].thrust_model_factor, 0.3, kCopiedExactly);
  // Named: the servo output and the control surface count; not the seventh
  // rotor (beyond CA_ROTOR_COUNT), the servo's own range, nor the
  // parameters of other modules.
  EXPECT_TRUE(lists(imported.not_mapped, "PWM_MAIN_FUNC7 = 201")) << imported.yaml;
  EXPECT_TRUE(lists(imported.not_mapped, "CA_SV_CS_COUNT = 1"));
  EXPECT_FALSE(lists(imported.not_mapped, "CA_ROTOR6"));
  EXPECT_FALSE(lists(imported.not_mapped, "PWM_MAIN_MIN7"));
  EXPECT_FALSE(lists(imported.not_mapped, "MPC_XY_VEL_MAX"));
  EXPECT_TRUE(lists(imported.notes, "2 more mixing and output parameters at 0"));
}

// Motors on AUX outputs and on a UAVCAN ESC, the timers' protocols and
// PX4's DShot setting: each motor's range from its own group, and every
// output parameter not taken named with why; no spin landing on a vehicle
// PX4 does not describe.
TEST(Px4Import, AuxAndUavcanMotorsAndProtocolsAreTakenOrNamedWithWhy) {
  config::Px4Parameters p;
  p.values = {{"CA_ROTOR_COUNT", 4},   {"CA_ROTOR0_PX", 0.2},   {"CA_ROTOR0_PY", 0.2},
              {"CA_ROTOR1_PX", -0.2},  {"CA_ROTOR1_PY", -0.2},  {"CA_ROTOR1_KM", 0.05},
              {"CA_ROTOR2_PX", 0.2},   {"CA_ROTOR2_PY", -0.2},  {"CA_ROTOR2_KM", -0.05},
              {"CA_ROTOR3_PX", -0.2},  {"CA_ROTOR3_PY", 0.2},   {"CA_ROTOR3_KM", -0.05},
              {"PWM_MAIN_FUNC1", 101}, {"PWM_MAIN_FUNC2", 102}, {"PWM_MAIN_MIN1", 1080},
              {"PWM_AUX_FUNC2", 103},  {"PWM_AUX_MIN2", 1100},  {"PWM_AUX_MAX2", 1900},
              {"PWM_AUX_DIS2", 950},   {"PWM_AUX_MIN1", 1200},  {"UAVCAN_EC_FUNC1", 104},
              {"PWM_MAIN_TIM0", -3},   {"PWM_AUX_TIM0", 400},   {"DSHOT_CONFIG", 600},
              {"PWM_MAIN_TIM1", -2}};
  const config::Px4Import imported = config::import_px4(p, "test");
  const config::Config c = config::load_config_text(imported.yaml, "imported");
  ASSERT_EQ(c.motors(), 4);
  EXPECT_EQ(c.outputs[0].min, 1080.0);  // MAIN 1
  EXPECT_EQ(c.outputs[2].min, 1100.0);  // AUX 2, not AUX 1's
  EXPECT_EQ(c.outputs[2].max, 1900.0);
  EXPECT_EQ(c.outputs[2].disarmed, 950.0);
  EXPECT_EQ(c.outputs[3].min, 1000.0);  // the UAVCAN ESC: PX4's default range
  EXPECT_TRUE(lists(imported.notes, "motor 4 is on UAVCAN ESC 1, an ESC motormix cannot drive"));
  EXPECT_NE(imported.yaml.find("motor 3 on AUX 2"), std::string::npos) << imported.yaml;
  EXPECT_TRUE(lists(imported.not_mapped, "PWM_MAIN_TIM0 = -3: DShot600"));
  EXPECT_TRUE(lists(imported.not_mapped, "hardware.protocol: dshot600"));
  EXPECT_TRUE(lists(imported.not_mapped, "PWM_MAIN_TIM1 = -2: DShot1200"));
  EXPECT_TRUE(lists(imported.not_mapped, "PWM_AUX_TIM0 = 400: PWM at 400 Hz"));
  EXPECT_TRUE(lists(imported.not_mapped, "DSHOT_CONFIG = 600: DShot 600"));
  // AUX 1 drives no motor: its range is not a motor's, not named.
  EXPECT_FALSE(lists(imported.not_mapped, "PWM_AUX_MIN1"));
  for (const std::string& n : imported.not_mapped)
    EXPECT_EQ(n.find(": not mapped"), std::string::npos) << n;
  EXPECT_FALSE(c.motor_loss.has_value());
  EXPECT_NE(c.motor_loss_off.find("off"), std::string::npos) << c.motor_loss_off;
}

// A rotor a servo tilts in flight cannot be mixed by a fixed matrix: the
// import refuses it and says why. Control surfaces are named with why.
TEST(Px4Import, ATiltrotorIsRefusedAndControlSurfacesNamed) {
  config::Px4Parameters p;
  p.values = {{"CA_ROTOR_COUNT", 1}, {"CA_ROTOR0_TILT", 1}};
  try {
    config::import_px4(p, "test");
    ADD_FAILURE() << "a tiltrotor taken";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("CA_ROTOR0_TILT = 1: a rotor a servo tilts in flight"),
              std::string::npos)
        << e.what();
  }
  p.values = {{"CA_ROTOR_COUNT", 1}, {"CA_SV_CS_COUNT", 2}, {"CA_SV_CS0_TYPE", 1}};
  const config::Px4Import imported = config::import_px4(p, "test");
  EXPECT_TRUE(lists(imported.not_mapped, "CA_SV_CS_COUNT = 2: control surfaces"));
  EXPECT_TRUE(lists(imported.not_mapped, "CA_SV_CS0_TYPE = 1: control surfaces"));
}

TEST(Px4Import, ABeforeControlAllocationAirframeIsAPreset) {
  config::Px4Parameters p;
  p.values = {{"SYS_AUTOSTART", 6001}, {"MC_AIRMODE", 2}};
  const config::Px4Import imported = config::import_px4(p, "test");
  const config::Config c = config::load_config_text(imported.yaml, "imported");
  EXPECT_EQ(c.motors(), 6);
  EXPECT_EQ(named_airmode(c.airmode), Airmode::kRollPitchYaw);
  EXPECT_TRUE(lists(imported.notes, "preset hexa_x"));
  p.values = {{"SYS_AUTOSTART", 10016}};  // a quad wide frame: no preset
  EXPECT_THROW(config::import_px4(p, "test"), std::runtime_error);
}

TEST(Px4Import, DamagedOrForeignInputIsRefusedWithTheReason) {
  const auto expect_refused = [](const std::string& text, const std::string& why) {
    const std::string path = "/tmp/motormix-px4-import-" + std::to_string(::getpid());
    std::ofstream(path, std::ios::binary) << text;
    try {
      const config::Px4Parameters p = config::read_px4_parameters(path);
      config::import_px4(p, path);
      ADD_FAILURE() << "taken: " << text.substr(0, 40);
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    }
    std::remove(path.c_str());
  };
  expect_refused("1\t1\tCA_ROTOR_COUNT\tfour\t6\n", "is not a number");
  expect_refused("just some words\n", "not a parameter line");
  expect_refused(std::string("\x7f"
                             "ELF\0\0\0",
                             7),
                 "neither");
  expect_refused("1\t1\tCA_AIRFRAME\t1\t6\n1\t1\tCA_ROTOR_COUNT\t4\t6\n", "not a multicopter");
  expect_refused("1\t1\tCA_ROTOR_COUNT\t40\t6\n", "1 to 16 rotors");
  expect_refused("1\t1\tMPC_XY_VEL_MAX\t12\t9\n", "no multirotor geometry");
  EXPECT_THROW(config::read_px4_parameters("/nonexistent/x.params"), std::runtime_error);
  // A ULog cut short keeps the parameters before the cut.
  std::ifstream in(source_path("test/data/px4/sample_px4_events.ulg"), std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string path = "/tmp/motormix-px4-cut-" + std::to_string(::getpid()) + ".ulg";
  std::ofstream(path, std::ios::binary) << bytes.substr(0, bytes.size() / 3);
  const config::Px4Parameters cut = config::read_px4_parameters(path);
  EXPECT_EQ(cut.values.at("CA_ROTOR_COUNT"), 4.0);
  std::ofstream(path, std::ios::binary) << bytes.substr(0, 20);  // the header and no more
  EXPECT_THROW(config::read_px4_parameters(path), std::runtime_error);
  std::remove(path.c_str());
}

}  // namespace
}  // namespace motormix::test
