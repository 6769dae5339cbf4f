// A recorded team-quad flight replayed by lcm-logplayer into a running
// `motormix run`, on a private bus. Every published output is checked against
// the document's mixer applied to the exact inputs it names (setpoint_utime,
// pid_utime), and the disarmed phases and shutdown against the safety rules.

#include "integration/bus_recorder.hpp"
#include "integration/process.hpp"
#include "seed000_reference.hpp"
#include "test_support.hpp"

#include <motormix/pid_t.hpp>
#include <motormix/setpoint_t.hpp>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <csignal>
#include <cstdlib>
#include <fstream>
#include <map>

namespace motormix::test {
namespace {

using namespace std::chrono_literals;

struct FlightLog {
  std::map<std::int64_t, setpoint_t> setpoints;  // by utime
  std::map<std::int64_t, pid_t> pids;
  double duration_s = 0.0;
};

FlightLog read_log(const std::string& path, const std::string& setpoint_channel,
                   const std::string& pid_channel) {
  FlightLog log;
  lcm::LogFile file(path, "r");
  EXPECT_TRUE(file.good()) << path;
  std::int64_t first = -1;
  std::int64_t last = 0;
  while (const lcm::LogEvent* ev = file.readNextEvent()) {
    if (first < 0) first = ev->timestamp;
    last = ev->timestamp;
    if (ev->channel == setpoint_channel) {
      setpoint_t m;
      if (m.decode(ev->data, 0, static_cast<int>(ev->datalen)) > 0) log.setpoints[m.utime] = m;
    } else if (ev->channel == pid_channel) {
      pid_t m;
      if (m.decode(ev->data, 0, static_cast<int>(ev->datalen)) > 0) log.pids[m.utime] = m;
    }
  }
  log.duration_s = static_cast<double>(last - first) / 1e6;
  return log;
}

bool in_private_bus() {
  const char* flag = std::getenv("MOTORMIX_PRIVATE_BUS");
  return flag != nullptr && std::string(flag) == "1";
}

// The offline replay: same mixer and loop logic, log time as the clock.
std::vector<motor_pwm_t> replay_outputs(const std::string& log, const std::string& out,
                                        const std::string& channel) {
  const std::string cmd = std::string(motormix_binary()) + " replay --config " +
                          source_path("config/team_quad.yaml") + " --set output.spool_up_s=0 " +
                          log + " " + out + " > /dev/null 2>&1";
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
  std::vector<motor_pwm_t> outputs;
  lcm::LogFile file(out, "r");
  while (const lcm::LogEvent* ev = file.readNextEvent()) {
    if (ev->channel != channel) continue;
    motor_pwm_t m{};
    if (m.decode(ev->data, 0, static_cast<int>(ev->datalen)) > 0) outputs.push_back(m);
  }
  return outputs;
}

std::string read_bytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

TEST(ReplayFlight, TeamQuadFlightThroughTheRunningMixer) {
  ASSERT_TRUE(in_private_bus()) << "run this test through scripts/private-bus (ctest does)";
  const config::Config config = team_quad_config();
  const std::string log_path = source_path("test/data/flights/team_quad.lcmlog");
  const FlightLog flight = read_log(log_path, config.channels.setpoint, config.channels.pid);
  ASSERT_GT(flight.setpoints.size(), 100U);
  ASSERT_GT(flight.pids.size(), 1000U);

  BusRecorder bus(config.channels.motor_pwm, config.channels.status);
  ASSERT_TRUE(bus.good());

  // Staleness is exercised elsewhere; here generous timeouts keep a loaded CI
  // machine's scheduling hiccups from turning a correct run into a failsafe.
  ChildProcess mixer({motormix_binary(), "run", "--config", source_path("config/team_quad.yaml"),
                      "--set", "output.spool_up_s=0", "--set", "inputs.setpoint_timeout_ms=2000",
                      "--set", "inputs.pid_timeout_ms=2000"});
  ASSERT_TRUE(mixer.started());
  ASSERT_TRUE(bus.wait_until([](const auto& pwm, const auto&) { return !pwm.empty(); }, 10s))
      << "motormix published nothing";

  ChildProcess player({"lcm-logplayer", log_path});
  ASSERT_TRUE(player.started());
  const auto budget = std::chrono::milliseconds(static_cast<int>(flight.duration_s * 1000) + 60000);
  ASSERT_EQ(player.wait_for(budget), 0) << "lcm-logplayer did not finish";

  // Wait until an output names the last setpoint (a disarm) and the last pid
  // message: then the mixer has handled every input of the flight.
  const std::int64_t last_setpoint = flight.setpoints.rbegin()->first;
  const std::int64_t last_pid = flight.pids.rbegin()->first;
  ASSERT_TRUE(bus.wait_until(
      [&](const auto& pwm, const auto&) {
        return !pwm.empty() && pwm.back().setpoint_utime == last_setpoint &&
               pwm.back().pid_utime == last_pid;
      },
      10s));

  const std::size_t before_stop = bus.status().size();
  mixer.signal(SIGTERM);
  ASSERT_EQ(mixer.wait_for(10s), 0) << "motormix did not exit cleanly on SIGTERM";
  // Its final status comes after its final outputs: once it is here, so are they.
  ASSERT_TRUE(bus.wait_until(
      [&](const auto&, const auto& status) {
        return status.size() > before_stop && status.back().state == mixer_status_t::STATE_DISARMED;
      },
      10s));

  const std::vector<motor_pwm_t> outputs = bus.pwm();
  EXPECT_EQ(bus.undecodable(), 0);
  ASSERT_FALSE(outputs.back().armed) << "the last output before exit must be disarmed";

  std::size_t armed = 0;
  std::size_t with_roll = 0;
  std::size_t with_pitch = 0;
  std::size_t with_yaw = 0;
  bool seen_armed = false;
  for (const motor_pwm_t& out : outputs) {
    ASSERT_EQ(out.num_motors, 4);
    ASSERT_EQ(out.pwm.size(), 4U);
    for (int i = 0; i < 4; ++i) {
      const double pwm = out.pwm[static_cast<std::size_t>(i)];
      ASSERT_TRUE(std::isfinite(pwm));
      ASSERT_TRUE(out.armed ? (pwm >= 1150.0 && pwm <= 1924.0) : pwm == 1000.0) << pwm;
    }
    const auto sp = flight.setpoints.find(out.setpoint_utime);
    if (!out.armed) {
      // Disarmed only before arming, or when the setpoint in force says so.
      if (seen_armed && sp != flight.setpoints.end()) {
        EXPECT_FALSE(sp->second.armed) << "disarmed output while armed setpoint " << sp->first;
      }
      continue;
    }
    seen_armed = true;
    ++armed;
    ASSERT_NE(sp, flight.setpoints.end()) << "output names an unknown setpoint";
    const auto pid = flight.pids.find(out.pid_utime);
    ASSERT_NE(pid, flight.pids.end()) << "output names an unknown pid message";
    ASSERT_TRUE(sp->second.armed) << "armed output from a disarmed setpoint";
    const Seed000Input in{sp->second.throttle, pid->second.roll, pid->second.pitch, sp->second.yaw};
    with_roll += in.roll != 0.0;
    with_pitch += in.pitch != 0.0;
    with_yaw += in.yaw != 0.0;
    const auto power = seed000_power(in);
    for (int i = 0; i < 4; ++i) {
      const auto k = static_cast<std::size_t>(i);
      ASSERT_NEAR(out.command[k], power[k], kFloatCommand)
          << "motor " << i << ", setpoint " << sp->first << ", pid " << pid->first;
      ASSERT_NEAR(out.pwm[k], seed000_pwm(power[k]), kFloatPwmUs) << "motor " << i;
    }
  }
  // The flight covers every axis while armed, at 400 Hz for several seconds.
  EXPECT_GT(armed, 1000U);
  EXPECT_GT(with_roll, 100U);
  EXPECT_GT(with_pitch, 100U);
  EXPECT_GT(with_yaw, 100U);

  // The offline replay of the same log gives the same output for the same
  // inputs (both float32 from one double computation: equal to the bit).
  std::map<std::pair<std::int64_t, std::int64_t>, std::vector<float>> offline;
  for (const motor_pwm_t& m : replay_outputs(
           log_path, ::testing::TempDir() + "/live_vs_replay.lcmlog", config.channels.motor_pwm)) {
    if (m.armed) offline[{m.setpoint_utime, m.pid_utime}] = m.pwm;
  }
  std::size_t shared = 0;
  for (const motor_pwm_t& out : outputs) {
    if (!out.armed) continue;
    const auto it = offline.find({out.setpoint_utime, out.pid_utime});
    if (it == offline.end()) continue;  // the two loops tick at different instants
    ++shared;
    EXPECT_EQ(it->second, out.pwm);
  }
  EXPECT_GT(shared, armed / 4) << "live and offline outputs hardly overlap";

  const mixer_status_t last = bus.status().back();
  EXPECT_EQ(last.setpoint_received, static_cast<std::int64_t>(flight.setpoints.size()));
  EXPECT_EQ(last.pid_received, static_cast<std::int64_t>(flight.pids.size()));
  EXPECT_EQ(last.failsafe_events, 0);
  EXPECT_EQ(last.rejected_decode + last.rejected_nonfinite + last.rejected_range, 0);
}

TEST(OfflineReplay, MatchesTheDocumentAndTheLiveProcess) {
  const config::Config config = team_quad_config();
  const std::string log_path = source_path("test/data/flights/team_quad.lcmlog");
  const FlightLog flight = read_log(log_path, config.channels.setpoint, config.channels.pid);
  const std::string dir = ::testing::TempDir();
  const auto a = replay_outputs(log_path, dir + "/replay_a.lcmlog", config.channels.motor_pwm);
  replay_outputs(log_path, dir + "/replay_b.lcmlog", config.channels.motor_pwm);
  EXPECT_EQ(read_bytes(dir + "/replay_a.lcmlog"), read_bytes(dir + "/replay_b.lcmlog"))
      << "replay is not deterministic";

  std::size_t armed = 0;
  for (const motor_pwm_t& out : a) {
    if (!out.armed) continue;
    ++armed;
    const auto sp = flight.setpoints.find(out.setpoint_utime);
    const auto pid = flight.pids.find(out.pid_utime);
    ASSERT_TRUE(sp != flight.setpoints.end() && pid != flight.pids.end());
    const auto power =
        seed000_power({sp->second.throttle, pid->second.roll, pid->second.pitch, sp->second.yaw});
    for (std::size_t i = 0; i < 4; ++i) {
      ASSERT_NEAR(out.pwm[i], seed000_pwm(power[i]), kFloatPwmUs);
    }
  }
  // 12 s armed at 400 Hz, as in the log.
  EXPECT_NEAR(static_cast<double>(armed), 12.0 * 400.0, 0.01 * 12.0 * 400.0);
}

}  // namespace
}  // namespace motormix::test

namespace motormix::test {
namespace {

// replay writes its logs itself, through one large buffer: the bytes must be
// exactly what LCM's own writer makes of the same events.
TEST(ReplayLogFormat, ByteIdenticalToLcmsOwnWriter) {
  const std::string ours = ::testing::TempDir() + "replay_format_ours.lcmlog";
  const std::string lcms = ::testing::TempDir() + "replay_format_lcm.lcmlog";
  replay_outputs(source_path("test/data/flights/team_quad.lcmlog"), ours, "MOTOR_PWM");
  {
    lcm::LogFile in(ours, "r");
    lcm::LogFile out(lcms, "w");
    ASSERT_TRUE(in.good() && out.good());
    int events = 0;
    while (const lcm::LogEvent* ev = in.readNextEvent()) {
      lcm::LogEvent copy = *ev;
      out.writeEvent(&copy);
      ++events;
    }
    ASSERT_GT(events, 10000);
  }
  const std::string a = read_bytes(ours);
  const std::string b = read_bytes(lcms);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_TRUE(a == b);
}

}  // namespace
}  // namespace motormix::test
