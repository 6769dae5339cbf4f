// Regression suite: one flight from test/data/flights, one configuration.
// lcm-logplayer replays the flight into a running `motormix run` on a private
// bus; every recorded output is checked against the golden file (the offline
// replay's output for the same pair of inputs, test/data/golden/NAME.csv)
// and against the invariants: finite, within range, disarmed when the
// setpoint in force says so. Correspondence is by the inputs each output
// names, never by wall-clock timing.
//
// With --sign yes, the flight is signed first (`motormix sign-log --now`,
// a fresh key) and the mixer runs under security.mode require: the outputs
// must be the same golden ones, and no input refused.
//
//   regression_tests --flight F --config C --golden G [--sign yes] [--set key=value ...]

#include "integration/bus_recorder.hpp"
#include "integration/process.hpp"
#include "integration/udp_drops.hpp"
#include "test_support.hpp"

#include <motormix/setpoint_t.hpp>
#include <motormix/signing.hpp>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <tuple>

namespace motormix::test {
namespace {

using namespace std::chrono_literals;

struct Args {
  std::string flight;
  std::string config;
  std::string golden;
  std::vector<std::string> overrides;
  bool sign = false;
};
Args g_args;

// Golden PWM is written to 0.001 (both sides come from the same double
// computation, so only that rounding separates them).
constexpr double kGoldenPwm = 1e-3;
// Twice real time: the flights keep their meaning (a 0.4 s silence is still
// longer than any timeout) and the suite runs in half the time.
constexpr int kPlaybackSpeed = 2;

// Key: setpoint utime, pid utime, and the failure set in force (0 unless the
// golden file has a failed_motors column).
using GoldenKey = std::tuple<std::int64_t, std::int64_t, std::int64_t>;
struct Golden {
  bool keyed_by_failures = false;
  std::map<GoldenKey, std::vector<double>> armed;  // pwm then direction
};

Golden read_golden(const std::string& path) {
  Golden g;
  std::ifstream f(path);
  EXPECT_TRUE(f.good()) << path << " (regenerate with scripts/regen-golden)";
  for (std::string line; std::getline(f, line);) {
    if (line.rfind("# setpoint_utime,pid_utime,failed_motors", 0) == 0) g.keyed_by_failures = true;
    if (line.empty() || line[0] == '#') continue;
    std::stringstream s(line);
    std::string cell;
    std::vector<double> values;
    std::int64_t sp = 0;
    std::int64_t pid = 0;
    std::int64_t failed = 0;
    const int keys = g.keyed_by_failures ? 3 : 2;
    for (int i = 0; std::getline(s, cell, ','); ++i) {
      if (i == 0) {
        sp = std::stoll(cell);
      } else if (i == 1) {
        pid = std::stoll(cell);
      } else if (i < keys) {
        failed = std::stoll(cell);
      } else {
        values.push_back(std::stod(cell));
      }
    }
    g.armed[{sp, pid, failed}] = values;
  }
  return g;
}

std::map<std::int64_t, bool> setpoint_armed(const std::string& log, const std::string& channel) {
  std::map<std::int64_t, bool> out;
  lcm::LogFile file(log, "r");
  while (const lcm::LogEvent* ev = file.readNextEvent()) {
    if (ev->channel != channel) continue;
    setpoint_t m{};
    if (m.decode(ev->data, 0, static_cast<int>(ev->datalen)) > 0) out[m.utime] = m.armed;
  }
  return out;
}

TEST(Regression, LiveReplayMatchesGoldenAndInvariants) {
  const char* flag = std::getenv("MOTORMIX_PRIVATE_BUS");
  ASSERT_TRUE(flag && std::string(flag) == "1") << "run through scripts/private-bus";
  const std::string config_path = source_path("config/" + g_args.config);
  const std::string recorded = source_path("test/data/flights/" + g_args.flight + ".lcmlog");
  std::string flight = recorded;
  std::vector<std::string> overrides = g_args.overrides;
  namespace fs = std::filesystem;
  const fs::path dir =
      fs::temp_directory_path() / ("motormix_regression_" + std::to_string(getpid()));
  if (g_args.sign) {
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::string key = (dir / "bus.key").string();
    signing::write_new_key(key);
    overrides.push_back("security.mode=require");
    overrides.push_back("security.key_file=" + key);
  }
  const config::Config config = config::load_config_file(config_path, overrides);
  const Golden golden = read_golden(source_path("test/data/golden/" + g_args.golden + ".csv"));
  ASSERT_GT(golden.armed.size(), 100U);
  const auto armed_by_setpoint = setpoint_armed(recorded, config.channels.setpoint);

  BusRecorder bus(config.channels.motor_pwm, config.channels.status);
  std::vector<std::string> sets;
  for (const auto& o : overrides) {
    sets.push_back("--set");
    sets.push_back(o);
  }
  std::vector<std::string> argv = {motormix_binary(), "run", "--config", config_path};
  argv.insert(argv.end(), sets.begin(), sets.end());
  ChildProcess mixer(argv);
  ASSERT_TRUE(bus.wait_until([](const auto& pwm, const auto&) { return !pwm.empty(); }, 10s));
  if (g_args.sign) {
    // Stamped from now, so that the mixer takes the copy as fresh.
    flight = (dir / "signed.lcmlog").string();
    std::vector<std::string> sign = {motormix_binary(), "sign-log", "--now", "--config",
                                     config_path};
    sign.insert(sign.end(), sets.begin(), sets.end());
    sign.push_back(recorded);
    sign.push_back(flight);
    ChildProcess signer(sign);
    ASSERT_EQ(signer.wait_for(30s), 0);
  }
  const long drops_before = udp_receive_buffer_drops();
  ASSERT_GE(drops_before, 0) << "cannot read Udp RcvbufErrors from /proc/net/snmp";
  ChildProcess player({"lcm-logplayer", "-s", std::to_string(kPlaybackSpeed), flight});
  ASSERT_EQ(player.wait_for(120s), 0);
  const std::int64_t last_setpoint = armed_by_setpoint.rbegin()->first;
  const bool saw_last_setpoint = bus.wait_until(
      [&](const auto& pwm, const auto&) {
        return !pwm.empty() && pwm.back().setpoint_utime == last_setpoint;
      },
      10s);
  mixer.signal(SIGTERM);
  ASSERT_EQ(mixer.wait_for(10s), 0);
  // A datagram the kernel dropped (a full receive buffer on a loaded
  // machine) never reached motormix: the outputs until the next message on
  // that channel name a pair of inputs the golden replay, which saw every
  // message, never formed. Only then are such outputs tolerated, counted,
  // and only a few of them; with no drop every output must match.
  const long kernel_drops = udp_receive_buffer_drops() - drops_before;
  ASSERT_TRUE(saw_last_setpoint || kernel_drops > 0)
      << "no output named the flight's last setpoint, and the kernel dropped nothing";

  const int n = config.motors();
  std::size_t armed = 0;
  std::size_t compared = 0;
  std::size_t unmatched = 0;  // only when the kernel dropped datagrams
  for (const motor_pwm_t& out : bus.pwm()) {
    ASSERT_EQ(out.num_motors, n);
    for (int i = 0; i < n; ++i) {
      const auto k = static_cast<std::size_t>(i);
      const OutputChannel& ch = config.outputs[k];
      ASSERT_TRUE(std::isfinite(out.pwm[k]));
      if (out.armed && ((out.failed_motors >> i) & 1)) {
        ASSERT_EQ(out.pwm[k], static_cast<float>(ch.disarmed)) << "a failed motor is stopped";
      } else if (out.armed) {
        ASSERT_GE(out.pwm[k], ch.min);
        ASSERT_LE(out.pwm[k], ch.max);
      } else {
        ASSERT_EQ(out.pwm[k], static_cast<float>(ch.disarmed));
        ASSERT_EQ(out.direction[k], 0);
      }
    }
    const auto sp = armed_by_setpoint.find(out.setpoint_utime);
    if (sp != armed_by_setpoint.end() && !sp->second) {
      ASSERT_FALSE(out.armed) << "armed output while the setpoint in force says disarmed";
    }
    if (!out.armed) continue;
    ++armed;
    const auto g = golden.armed.find(
        {out.setpoint_utime, out.pid_utime, golden.keyed_by_failures ? out.failed_motors : 0});
    if (g == golden.armed.end() && kernel_drops > 0) {
      ++unmatched;
      continue;
    }
    ASSERT_NE(g, golden.armed.end()) << "armed output for inputs (" << out.setpoint_utime << ", "
                                     << out.pid_utime << ") that the golden replay never armed";
    ++compared;
    for (int i = 0; i < n; ++i) {
      const auto k = static_cast<std::size_t>(i);
      ASSERT_NEAR(out.pwm[k], g->second[k], kGoldenPwm) << "motor " << i;
      const bool has_direction = g->second.size() == 2 * static_cast<std::size_t>(n);
      const int direction =
          has_direction ? static_cast<int>(g->second[k + static_cast<std::size_t>(n)]) : 0;
      ASSERT_EQ(out.direction[k], direction);
    }
  }
  // Armed for (nearly) as long as the flight asks: the share of armed
  // setpoints times the flight's duration (played faster), at the loop rate.
  std::size_t armed_setpoints = 0;
  for (const auto& [utime, is_armed] : armed_by_setpoint) armed_setpoints += is_armed;
  const double span_s =
      static_cast<double>(armed_by_setpoint.rbegin()->first - armed_by_setpoint.begin()->first) /
      1e6;
  const double expected = static_cast<double>(armed_setpoints) /
                          static_cast<double>(armed_by_setpoint.size()) * span_s *
                          config.loop_rate_hz / kPlaybackSpeed;
  EXPECT_GT(static_cast<double>(armed), 0.5 * expected);  // a loaded machine drops late cycles
  // A dropped input leaves at most a few cycles unmatched; a broken mixer
  // would leave most of them.
  constexpr double kUnmatchedShare = 0.05;
  EXPECT_LE(static_cast<double>(unmatched), kUnmatchedShare * static_cast<double>(armed))
      << unmatched << " outputs name input pairs the golden replay never formed; the kernel "
      << "dropped " << kernel_drops << " datagrams on the private bus";
  if (unmatched > 0) {
    std::printf("%zu of %zu armed outputs not compared: the kernel dropped %ld datagrams\n",
                unmatched, armed, kernel_drops);
  }
  EXPECT_EQ(compared + unmatched, armed);
  const std::vector<mixer_status_t> status = bus.status();
  ASSERT_FALSE(status.empty());
  const mixer_status_t& last = status.back();
  if (g_args.sign) {
    EXPECT_EQ(last.security_mode, mixer_status_t::SECURITY_REQUIRE);
    EXPECT_GT(last.signed_received, 0);
    EXPECT_GT(bus.signed_messages(), 0) << "the mixer's outputs were not signed";
    fs::remove_all(dir);
  }
  EXPECT_EQ(last.rejected_unsigned + last.rejected_bad_signature + last.rejected_replayed +
                last.rejected_stale_signature,
            0);
}

}  // namespace
}  // namespace motormix::test

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  auto& a = motormix::test::g_args;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string key = argv[i];
    const std::string value = argv[i + 1];
    if (key == "--flight") a.flight = value;
    if (key == "--config") a.config = value;
    if (key == "--golden") a.golden = value;
    if (key == "--set") a.overrides.push_back(value);
    if (key == "--sign") a.sign = value == "yes";
  }
  if (a.flight.empty() || a.config.empty() || a.golden.empty()) {
    std::fprintf(stderr,
                 "usage: regression_tests --flight F --config C --golden G [--set k=v ...]\n");
    return 2;
  }
  return RUN_ALL_TESTS();
}
