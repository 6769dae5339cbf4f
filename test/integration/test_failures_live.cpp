// Motor failures, battery compensation and the monitor, with `motormix run`
// as a process on a private bus; and the sagging-battery flight through the
// offline replay. Every wait is on messages with a bounded timeout; every
// loop is bounded in count.

#include "integration/mixer_fixture.hpp"

#include <motormix/battery_t.hpp>
#include <motormix/motor_status_t.hpp>

#include <lcm/lcm-cpp.hpp>

#include <array>
#include <cstdio>
#include <memory>

namespace motormix::test {
namespace {

class FailuresLive : public MixerProcessTest {
 protected:
  void send_status(std::vector<std::int8_t> failed) {
    motor_status_t m{};
    m.utime = wall_us();
    m.num_motors = static_cast<int32_t>(failed.size());
    m.failed = std::move(failed);
    pilot_->message(config_.channels.motor_status, m);
  }
};

// Runs a shell command, returns its exit code and standard output.
std::pair<int, std::string> capture(const std::string& cmd) {
  std::string out;
  FILE* p = popen(cmd.c_str(), "r");
  if (p == nullptr) return {-1, out};
  std::array<char, 4096> buf{};
  while (std::fgets(buf.data(), static_cast<int>(buf.size()), p) != nullptr) out += buf.data();
  const int status = pclose(p);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

TEST_F(FailuresLive, MotorStatusStopsTheMotorAndTheOthersTakeOver) {
  start({"mixer.strategy=optimal", "inputs.yaw_source=setpoint"}, "config/hexa_x.yaml");
  arm();
  // m3 reported dead: its output goes to the disarmed value, the others rise.
  const int n = config_.motors();
  bool seen = false;
  for (int k = 0; k < 200 && !seen; ++k) {
    send_status({0, 0, 1, 0, 0, 0});
    seen = fly_until(
        true, 0.5, [](const motor_pwm_t& m) { return m.armed && m.failed_motors == 0b100; }, 5);
  }
  ASSERT_TRUE(seen);
  const motor_pwm_t out = bus_->pwm().back();
  EXPECT_EQ(out.pwm[2], static_cast<float>(config_.outputs[2].disarmed));
  EXPECT_EQ(out.command[2], 0.0F);
  double sum = 0.0;
  for (int i = 0; i < n; ++i) sum += out.command[static_cast<std::size_t>(i)];
  EXPECT_NEAR(sum, 3.0, 1e-4) << "five motors make the thrust six made (healthy units)";
  ASSERT_TRUE(bus_->wait_until(
      [](const auto&, const auto& s) {
        return !s.empty() && s.back().failed_motors == 0b100 &&
               s.back().failure_handling == mixer_status_t::FAILURE_REALLOCATED;
      },
      2s));
  // Hostile and wrong-sized reports change nothing and are counted.
  send_status({1, 0, 0, 0});  // four motors on a hexa
  std::vector<std::uint8_t> hostile(21, 0);
  hostile[16] = 0x7f;
  hostile[17] = hostile[18] = hostile[19] = 0xff;  // num_motors 2^31 - 1
  pilot_->raw(config_.channels.motor_status, hostile);
  ASSERT_TRUE(bus_->wait_until(
      [](const auto&, const auto& s) {
        return !s.empty() && s.back().rejected_size >= 1 && s.back().rejected_decode >= 1;
      },
      2s));
  ASSERT_TRUE(fly_until(true, 0.5, [](const motor_pwm_t& m) { return m.failed_motors == 0b100; }));
  // The detector clears it.
  bool cleared = false;
  for (int k = 0; k < 200 && !cleared; ++k) {
    send_status({0, 0, 0, 0, 0, 0});
    cleared = fly_until(
        true, 0.5, [](const motor_pwm_t& m) { return m.failed_motors == 0; }, 5);
  }
  EXPECT_TRUE(cleared);
  stop_and_expect_disarmed_exit();
}

TEST_F(FailuresLive, BatteryCompensatesAndStopsWhenTheVoltageGoesStale) {
  start({"mixer.strategy=clip", "inputs.yaw_source=setpoint",
         "battery={nominal_v: 16.8, timeout_ms: 300, filter_hz: 5}"},
        "config/hexa_x.yaml");
  arm();
  bool compensated = false;
  for (int k = 0; k < 300 && !compensated; ++k) {
    battery_t b{};
    b.utime = wall_us();
    b.voltage = 14.0F;
    pilot_->message(config_.channels.battery, b);
    compensated = fly_until(
        true, 0.5, [](const motor_pwm_t& m) { return m.armed && m.command[0] > 0.5F * 1.19F; }, 5);
  }
  ASSERT_TRUE(compensated);
  // The status says so while the inputs keep coming: the pilot and the
  // battery monitor go on publishing (bounded in count) until a status shows
  // the compensation. Waiting for it with the inputs silent let them go
  // stale on a loaded machine (a status 300 ms late finds the voltage stale
  // and the setpoint in failsafe), which is not what this checks.
  bool reported = false;
  for (int k = 0; k < 400 && !reported; ++k) {
    battery_t b{};
    b.utime = wall_us();
    b.voltage = 14.0F;
    pilot_->message(config_.channels.battery, b);
    pilot_->send(true, 0.5);
    reported = bus_->wait_until(
        [](const auto&, const auto& s) {
          return !s.empty() && s.back().battery_state == mixer_status_t::BATTERY_OK &&
                 s.back().thrust_gain > 1.19F;
        },
        5ms);
  }
  ASSERT_TRUE(reported);
  // The monitor goes silent: after its timeout, no compensation.
  ASSERT_TRUE(fly_until(
      true, 0.5, [](const motor_pwm_t& m) { return std::abs(m.command[0] - 0.5F) < 1e-5F; }, 400));
  ASSERT_TRUE(bus_->wait_until(
      [](const auto&, const auto& s) {
        return !s.empty() && s.back().battery_state == mixer_status_t::BATTERY_STALE &&
               s.back().thrust_gain == 1.0F;
      },
      2s));
  stop_and_expect_disarmed_exit();
}

TEST_F(FailuresLive, MonitorShowsARunningMixerOnce) {
  start({"mixer.failed_motors=[m2]"}, "config/hexa_x.yaml");
  const auto [rc, out] = capture(std::string(motormix_binary()) + " monitor --once --config " +
                                 source_path("config/hexa_x.yaml") + " 2>&1");
  EXPECT_EQ(rc, 0) << out;
  for (const char* needle : {"state     DISARMED", "m2 failed: reallocated", "  m6 ", "cycles"}) {
    EXPECT_NE(out.find(needle), std::string::npos) << needle << "\n" << out;
  }
  EXPECT_EQ(out.find("\x1b"), std::string::npos) << "--once prints no escape codes";
  // The live view redraws with ANSI and stops by itself.
  const auto [live_rc, live] =
      capture(std::string(motormix_binary()) + " monitor --duration 1 2>&1");
  EXPECT_EQ(live_rc, 0);
  EXPECT_NE(live.find("\x1b[H\x1b[2J"), std::string::npos);
  stop_and_expect_disarmed_exit();
}

TEST(MonitorAlone, NoMixerOnTheBusExitsNonZeroWithinSeconds) {
  ASSERT_TRUE(in_private_bus()) << "run through scripts/private-bus";
  const auto started = Clock::now();
  const auto [rc, out] = capture(std::string(motormix_binary()) + " monitor --once 2>&1");
  const auto took = Clock::now() - started;
  EXPECT_EQ(rc, 1);
  EXPECT_LT(took, 5s);
  EXPECT_NE(out.find("no mixer_status on channel 'MIXER_STATUS'"), std::string::npos) << out;
}

// The sagging-battery flight through the offline replay: the thrust gain
// follows nominal / filtered voltage while the monitor speaks, and is 1
// during its silence and never above max_gain; the 0 V glitch is rejected.
TEST(BatteryReplay, SaggingPackIsCompensatedAndFailuresOfTheMonitorAreNot) {
  const std::string in = source_path("test/data/flights/battery_sag.lcmlog");
  const std::string out = ::testing::TempDir() + "battery_sag_replay.lcmlog";
  const std::string cmd = std::string(motormix_binary()) + " replay --config " +
                          source_path("config/quad_x.yaml") +
                          " --set output.spool_up_s=0 --set battery.nominal_v=16.8 "
                          "--set status_rate_hz=400 --set "
                          "mixer.strategy=clip " +
                          in + " " + out + " > /dev/null 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  lcm::LogFile file(out, "r");
  ASSERT_TRUE(file.good());
  std::int64_t first = -1;
  int ok = 0;
  int stale = 0;
  int64_t rejected_range = 0;
  double largest_gain = 0.0;
  while (const lcm::LogEvent* ev = file.readNextEvent()) {
    if (first < 0) first = ev->timestamp;
    if (ev->channel != "MIXER_STATUS") continue;
    mixer_status_t s{};
    ASSERT_GT(s.decode(ev->data, 0, static_cast<int>(ev->datalen)), 0);
    const double t = static_cast<double>(ev->timestamp - first) / 1e6;
    rejected_range = s.rejected_range;
    largest_gain = std::max(largest_gain, static_cast<double>(s.thrust_gain));
    ASSERT_LE(s.thrust_gain, 1.5F);
    ASSERT_GE(s.thrust_gain, 1.0F);
    if (s.battery_state == mixer_status_t::BATTERY_OK) {
      ++ok;
      // The filter lags the sag by about 1/(2 pi 2 Hz) = 80 ms (0.03 V here);
      // right after the silence it restarts from one reading, with the full
      // 0.05 V (one sigma) measurement noise: four sigma plus the lag.
      constexpr double kVoltageTracking = 0.25;
      const double truth = 16.8 - (16.8 - 13.4) * std::min(1.0, t / 10.5);
      EXPECT_NEAR(s.battery_voltage, truth, kVoltageTracking) << "t " << t;
      EXPECT_NEAR(s.thrust_gain, std::clamp(16.8 / s.battery_voltage, 1.0, 1.5), 1e-4) << "t " << t;
    }
    // Last reading 5.987 s, the next 6.807 s, timeout 500 ms: stale from 6.487 s.
    if (t > 6.55 && t < 6.78) {
      EXPECT_EQ(s.battery_state, mixer_status_t::BATTERY_STALE) << "t " << t;
      EXPECT_EQ(s.thrust_gain, 1.0F) << "t " << t;
      ++stale;
    }
  }
  EXPECT_GT(ok, 3000);
  EXPECT_GT(stale, 80);
  EXPECT_EQ(rejected_range, 1) << "the 0 V glitch";
  EXPECT_GT(largest_gain, 1.2);
}

}  // namespace
}  // namespace motormix::test
