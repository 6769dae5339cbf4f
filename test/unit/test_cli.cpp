// `motormix mix` and `motormix run --check` as a user runs them.

#include "test_support.hpp"

#include <motormix/config/load_config.hpp>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <motormix/effectiveness/presets.hpp>

#include <array>
#include <cstdio>
#include <filesystem>
#include <set>

namespace motormix::test {
namespace {

struct Result {
  int exit_code = -1;
  std::string out;
};

Result run(const std::string& args) {
  const std::string cmd = std::string(motormix_binary()) + " " + args + " 2>/dev/null";
  FILE* pipe = popen(cmd.c_str(), "r");
  Result r;
  if (!pipe) return r;
  std::array<char, 4096> buf{};
  while (fgets(buf.data(), static_cast<int>(buf.size()), pipe)) r.out += buf.data();
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

const std::string kConfig = "--config " + source_path("config/team_quad.yaml");

TEST(Cli, MixPrintsJson) {
  const Result r = run("mix " + kConfig + " --throttle 0 --roll 0.5 --pitch 0 --yaw 0 --json");
  ASSERT_EQ(r.exit_code, 0);
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["pwm"].size(), 4U);
  EXPECT_NEAR(j["pwm"][0].get<double>(), 1246.75, kExact);
  EXPECT_NEAR(j["pwm"][1].get<double>(), 1150.0, kExact);
  EXPECT_NEAR(j["command"][2].get<double>(), 0.125, kExact);
  EXPECT_EQ(j["motors"][3], "RR");
  EXPECT_TRUE(j["unallocated"].contains("roll"));
  EXPECT_EQ(j["saturated_motors"]["lower"], nlohmann::json::array({1, 3}));
}

TEST(Cli, BadArgumentsExitTwo) {
  EXPECT_EQ(run("mix " + kConfig + " --throttle 2 --json").exit_code, 2);
  EXPECT_EQ(run("mix " + kConfig + " --roll nan --json").exit_code, 2);
  EXPECT_EQ(run("mix " + kConfig + " --roll abc").exit_code, 2);
  EXPECT_EQ(run("mix --throttle 0.5").exit_code, 2);
  EXPECT_EQ(run("mix --config /nonexistent.yaml").exit_code, 2);
  EXPECT_EQ(run("frobnicate").exit_code, 2);
  EXPECT_EQ(run("").exit_code, 2);
}

TEST(Cli, CheckValidatesWithoutTheBus) {
  const Result ok = run("run " + kConfig + " --check");
  EXPECT_EQ(ok.exit_code, 0);
  EXPECT_NE(ok.out.find("valid"), std::string::npos);
  EXPECT_EQ(run("run " + kConfig + " --check --set loop_rate_hz=3").exit_code, 2);
}

TEST(Cli, HelpAndVersion) {
  EXPECT_EQ(run("--help").exit_code, 0);
  EXPECT_EQ(run("mix --help").exit_code, 0);
  const Result v = run("--version");
  EXPECT_EQ(v.exit_code, 0);
  EXPECT_NE(v.out.find("motormix"), std::string::npos);
}

// config/ holds a commented example for every preset, and each passes
// `run --check` as shipped; one that signs (quad_x_field.yaml: detection,
// spin landing, hardware and security together) passes with a key put where
// its key_file says (a key cannot be shipped: it would be everyone's), and
// fails without one.
TEST(Cli, EveryBundledConfigChecksAndEveryPresetHasOne) {
  const std::string key =
      (std::filesystem::temp_directory_path() / ("motormix_cli_key_" + std::to_string(getpid())))
          .string();
  std::filesystem::remove(key);
  ASSERT_EQ(run("keygen " + key).exit_code, 0);
  std::set<std::string> covered;
  int signed_configs = 0;
  for (const auto& entry : std::filesystem::directory_iterator(source_path("config"))) {
    if (entry.path().extension() != ".yaml") continue;
    const std::string file = entry.path().string();
    SCOPED_TRACE(file);
    const config::Config c = config::load_config_file(file);
    if (c.security.mode != signing::Mode::kOff) {
      ++signed_configs;
      EXPECT_EQ(run("run --check --config " + file + " --set security.key_file=/nonexistent.key")
                    .exit_code,
                2);
      const Result r = run("run --check --config " + file + " --set security.key_file=" + key);
      EXPECT_EQ(r.exit_code, 0) << r.out;
      EXPECT_NE(r.out.find("failure detection: telemetry"), std::string::npos) << r.out;
      EXPECT_NE(r.out.find("motor loss: spin landing"), std::string::npos) << r.out;
      EXPECT_TRUE(c.failure_detection.has_value() && c.motor_loss.has_value());
      EXPECT_NE(c.hardware.driver, config::HardwareDriver::kNone);
    } else {
      EXPECT_EQ(run("run --check --config " + file).exit_code, 0);
    }
    covered.insert(c.geometry.name);
  }
  std::filesystem::remove(key);
  EXPECT_GE(signed_configs, 1) << "no bundled configuration uses all four field features";
  for (const std::string& preset : preset_names()) {
    EXPECT_EQ(covered.count(preset), 1U) << "no config/*.yaml for preset " << preset;
  }
}

// import px4-params: the configuration on stdout loads (what is not mapped
// goes to stderr); a missing file and one of another format exit 2.
TEST(Cli, ImportPx4ParamsWritesAConfigurationThatLoads) {
  const Result r = run("import px4-params " + source_path("test/data/px4/hexa_outputs.params"));
  ASSERT_EQ(r.exit_code, 0);
  const config::Config c = config::load_config_text(r.out, "stdout");
  EXPECT_EQ(c.motors(), 6);
  EXPECT_EQ(run("import px4-params /nonexistent.params").exit_code, 2);
  EXPECT_EQ(run("import px4-params " + source_path("config/quad_x.yaml")).exit_code, 2);
  EXPECT_EQ(run("import").exit_code, 2);
}

TEST(Cli, MatrixFormatsOfOtherStacks) {
  const Result px4 = run("matrix --preset hexa_x --format px4");
  EXPECT_EQ(px4.exit_code, 0);
  EXPECT_NE(px4.out.find("param set-default CA_ROTOR_COUNT 6"), std::string::npos);
  const Result ap = run("matrix --preset quad_x --format ardupilot");
  EXPECT_EQ(ap.exit_code, 0);
  EXPECT_NE(ap.out.find("MotorsMatrix:init(4)"), std::string::npos);
  // A table has no rotor positions: a usage error, not an empty file.
  const Result table = run("matrix --preset team_quad --format px4");
  EXPECT_EQ(table.exit_code, 2);
  EXPECT_TRUE(table.out.empty());
}

TEST(Cli, MixWithFailedMotorsAndBatteryVoltage) {
  const std::string hexa = "--config " + source_path("config/hexa_x.yaml");
  Result r = run("mix " + hexa + " --throttle 0.5 --failed 1,m4 --json");
  ASSERT_EQ(r.exit_code, 0);
  auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["failed_motors"], nlohmann::json::array({"m1", "m4"}));
  EXPECT_EQ(j["failure_handling"], "reallocated");
  EXPECT_EQ(j["command"][0].get<double>(), 0.0);
  EXPECT_EQ(j["pwm"][3].get<double>(), 900.0) << "stopped at the disarmed value";
  EXPECT_TRUE(j["axes_held"]["yaw"].get<bool>());
  EXPECT_TRUE(j["authority"].contains("roll"));
  // A quad with a motor out: yaw is lost, and said to be.
  r = run("mix --config " + source_path("config/quad_x.yaml") +
          " --throttle 0.5 --failed 2 --json");
  ASSERT_EQ(r.exit_code, 0);
  j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["failure_handling"], "axes lost");
  EXPECT_FALSE(j["axes_held"]["yaw"].get<bool>());
  EXPECT_EQ(run("mix " + hexa + " --failed 7").exit_code, 2);
  EXPECT_EQ(run("mix " + hexa + " --failed m9").exit_code, 2);
  // Battery: unfiltered gain for one evaluation; needs the section.
  EXPECT_EQ(run("mix " + hexa + " --throttle 0.5 --battery-voltage 14").exit_code, 2);
  r = run("mix " + hexa +
          " --set battery.nominal_v=16.8 --set mixer.strategy=clip --throttle 0.5 "
          "--battery-voltage 14 --json");
  ASSERT_EQ(r.exit_code, 0);
  j = nlohmann::json::parse(r.out);
  EXPECT_NEAR(j["thrust_gain"].get<double>(), 1.2, 1e-12);
  EXPECT_NEAR(j["command"][0].get<double>(), 0.6, 1e-9);
  EXPECT_EQ(run("mix " + hexa + " --set battery.nominal_v=16.8 --battery-voltage 2").exit_code, 2);
}

}  // namespace
}  // namespace motormix::test
