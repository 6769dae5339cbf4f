// Bidirectional DShot end to end: the bundled team-quad flight through
// `motormix run` (its failure detector reading ESC telemetry only) and
// `motormix output` (bidirectional DShot600) to the simulated chip, whose
// pins carry emulated ESCs answering every frame with their motor's eRPM
// (their motors turning as the throttle says). The output publishes the
// replies as esc_telemetry_t; once the flight is armed, one ESC's motor
// stops, and the detector must name it, from the replies alone, within the
// issue's 30 ms (plus what the simulated chip ran late).

#include "integration/process.hpp"
#include "realtime_bridge.hpp"
#include "test_paths.hpp"
#include "test_support.hpp"

#include <motormix/esc_telemetry_t.hpp>
#include <motormix/mixer_status_t.hpp>

#include <lcm/lcm-cpp.hpp>

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#ifndef MOTORMIX_FIRMWARE_ELF
#error "MOTORMIX_FIRMWARE_ELF: the firmware under test"
#endif

namespace motormix::test {
namespace {

constexpr double kDetectionBoundMs = 30.0;  // the issue's, from the motor stopping
constexpr int kStoppedChannel = 1;          // motor 2
// Every frame's replies on the bus: 1000 a second, a message per frame
// with a reply; the real-time simulation may lose a few. Counted over the
// part of the second the simulated chip ran (realtime_bridge.hpp); a run
// where it ran less than kMinRanShare of it says nothing.
constexpr double kRepliesPerSecond = 875.0;
constexpr double kMinRanShare = 0.5;
// How late the simulated chip may be without its clock stopping (the
// bridge catches up past a millisecond).
constexpr double kChipLateMs = 1.0;

std::int64_t wall_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// mixer_status_t's detection and esc_telemetry_t's arrivals, from a thread
// of their own.
class Listener {
 public:
  explicit Listener(lcm::LCM& lcm) : lcm_(lcm) {
    lcm_.subscribe("MIXER_STATUS", &Listener::on_status, this)->setQueueCapacity(10000);
    lcm_.subscribe("ESC_TELEMETRY", &Listener::on_telemetry, this)->setQueueCapacity(100000);
    thread_ = std::thread([this] {
      while (!stop_) lcm_.handleTimeout(20);
    });
  }
  ~Listener() {
    stop_ = true;
    thread_.join();
  }
  struct Detection {
    std::int32_t motors = 0;
    int by = 0, motor = 0;
    std::int64_t utime = 0;
  };
  Detection detection() {
    std::lock_guard<std::mutex> lock(mutex_);
    return detection_;
  }
  std::uint64_t telemetry() const { return telemetry_.load(); }
  std::uint64_t named(int motor) const { return named_[motor].load(); }

 private:
  void on_status(const lcm::ReceiveBuffer*, const std::string&, const motormix::mixer_status_t* m) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (m->detected_motors != 0 && detection_.motors == 0)
      detection_ = {m->detected_motors, m->detected_by, m->detected_motor, m->detected_utime};
  }
  void on_telemetry(const lcm::ReceiveBuffer*, const std::string&,
                    const motormix::esc_telemetry_t* m) {
    ++telemetry_;
    for (int i = 0; i < m->count; ++i)
      if (m->motor[static_cast<std::size_t>(i)] >= 1 && m->motor[static_cast<std::size_t>(i)] <= 4)
        ++named_[m->motor[static_cast<std::size_t>(i)] - 1];
  }
  lcm::LCM& lcm_;
  std::mutex mutex_;
  Detection detection_;
  std::atomic<std::uint64_t> telemetry_{0};
  std::atomic<std::uint64_t> named_[4] = {};
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

TEST(OutputEndToEnd, BidirectionalDshotRepliesFindAStoppedMotorThroughRunAndOutput) {
  avr::RealtimeBridge::Escs escs;
  escs.noise.seed = 23;
  avr::RealtimeBridge bridge(MOTORMIX_FIRMWARE_ELF, escs);
  // The team's quad, its detector on ESC telemetry alone.
  std::ifstream in(source_path("config/team_quad.yaml"));
  std::stringstream text;
  text << in.rdbuf() << "\nfailure_detection: {sources: [telemetry]}\n";
  const std::string config = "/tmp/motormix-e2e-bidir.yaml";
  std::ofstream(config) << text.str();
  const std::vector<std::string> hw = {
      "--set", "hardware.driver=serial",     "--set", "hardware.serial.device=" + bridge.device(),
      "--set", "hardware.protocol=dshot600", "--set", "hardware.bidirectional=true",
      "--set", "hardware.pulse_rate_hz=1000"};
  std::vector<std::string> output_argv = {motormix_binary(), "output", "--config", config};
  output_argv.insert(output_argv.end(), hw.begin(), hw.end());
  ChildProcess output(output_argv, "/tmp/motormix-e2e-bidir-output.log");
  ChildProcess mixer({motormix_binary(), "run", "--config", config},
                     "/tmp/motormix-e2e-bidir-run.log");
  lcm::LCM lcm;
  ASSERT_TRUE(lcm.good());
  Listener listener(lcm);
  std::this_thread::sleep_for(std::chrono::milliseconds(600));
  ChildProcess player({"lcm-logplayer", source_path("test/data/flights/team_quad.lcmlog")});
  std::this_thread::sleep_for(std::chrono::seconds(5));  // into the armed flight
  const std::uint64_t before = listener.telemetry();
  const std::uint64_t named_before = listener.named(kStoppedChannel);
  const std::int64_t second_from = avr::steady_us();
  std::this_thread::sleep_for(std::chrono::seconds(1));
  const std::int64_t second_to = avr::steady_us();
  const std::uint64_t per_second = listener.telemetry() - before;
  const std::uint64_t named_per_second = listener.named(kStoppedChannel) - named_before;
  // Of that second, the part the simulated chip ran (a machine too busy to
  // run it in real time stops its clock: realtime_bridge.hpp).
  const double ran_share = 1.0 - static_cast<double>(bridge.absent_us(second_from, second_to)) /
                                     static_cast<double>(second_to - second_from);
  const Listener::Detection healthy = listener.detection();

  bridge.reset_max_lag();
  const std::int64_t stopped_at = wall_us();
  const std::int64_t stopped_steady = avr::steady_us();
  bridge.stop_motor(kStoppedChannel);
  Listener::Detection d;
  for (int i = 0; i < 100 && d.motors == 0; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    d = listener.detection();
  }
  player.signal(SIGKILL);
  const double latency_ms = static_cast<double>(d.utime - stopped_at) / 1000.0;
  std::printf(
      "bidirectional DShot600 at 1 kHz through run and output: %llu esc_telemetry_t a second "
      "(motor 2 named in %llu; the chip ran %.0f %% of that second); healthy flight: %s; motor 2 "
      "stopped: detected motor %d by %d after %.1f ms (chip late by %.2f ms at worst)\n",
      static_cast<unsigned long long>(per_second),
      static_cast<unsigned long long>(named_per_second), 100.0 * ran_share,
      healthy.motors == 0 ? "nothing declared" : "A MOTOR DECLARED", d.motor, d.by, latency_ms,
      bridge.max_lag_us() / 1000.0);
  // Every frame's replies on the bus, the stopped motor's too before it
  // stopped.
  ASSERT_GE(ran_share, kMinRanShare)
      << "the machine was too busy to run the simulated chip in real time";
  EXPECT_GE(static_cast<double>(per_second), kRepliesPerSecond * ran_share);
  EXPECT_GE(static_cast<double>(named_per_second), kRepliesPerSecond * ran_share);
  EXPECT_EQ(healthy.motors, 0) << "a detection in healthy flight";
  ASSERT_NE(d.motors, 0) << "the stopped motor was never found";
  EXPECT_EQ(d.motor, kStoppedChannel + 1);
  EXPECT_EQ(d.by, motormix::mixer_status_t::DETECTED_BY_TELEMETRY);
  EXPECT_GE(latency_ms, 0.0);
  EXPECT_LE(latency_ms, kDetectionBoundMs +
                            static_cast<double>(bridge.absent_us(
                                stopped_steady, stopped_steady + (d.utime - stopped_at))) /
                                1000.0 +
                            kChipLateMs);
  // At the real ATmega328P's receive depth: no byte of the output's lost.
  EXPECT_EQ(bridge.receiver().overruns, 0);
}

}  // namespace
}  // namespace motormix::test
