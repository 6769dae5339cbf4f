// `motormix run` as a process on a private bus: the publisher goes away and
// comes back, garbage arrives, SIGTERM arrives mid-flight, and the loop never
// runs fast. Every wait is on messages, with a bounded timeout; every loop is
// bounded in count; no check depends on how fast the machine is.

#include "integration/mixer_fixture.hpp"

#include <nlohmann/json.hpp>

#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <iterator>
#include <random>
#include <thread>

namespace motormix::test {
namespace {

class ProcessSafety : public MixerProcessTest {};

// The publisher stops: the first cycle past the timeout fails safe and
// disarms (checked in the mixer's own clock, from a status every cycle), never
// one before it, and a publisher that comes back still saying "armed" does
// not restart the motors.
TEST_F(ProcessSafety, PublisherDropoutFailsSafeInTheFirstCyclePastTheTimeout) {
  start({"status_rate_hz=400"});  // the team quad loops at 400 Hz: a status every cycle
  const auto timeout =
      std::chrono::milliseconds(static_cast<int>(config_.inputs.setpoint_timeout_s * 1e3));
  for (int trial = 0; trial < 5; ++trial) {
    SCOPED_TRACE("trial " + std::to_string(trial));
    arm();
    const std::size_t from = bus_->status().size();
    ASSERT_TRUE(wait_for_failsafe_status(from));
    const std::vector<CycleRecord> cycles = cycles_since(from);
    const auto failsafe = expect_failsafe_in_first_late_cycle(cycles);
    ASSERT_TRUE(failsafe.has_value());
    for (std::size_t k = *failsafe; k < cycles.size(); ++k) {
      EXPECT_FALSE(cycles[k].pwm.armed);
      for (float v : cycles[k].pwm.pwm) EXPECT_EQ(v, 1000.0F);
    }
    // Never before the timeout: the first disarmed output cannot arrive
    // sooner than the timeout after the older of the inputs the mixer held
    // began to be sent (causality, not speed: a slow machine only makes it
    // later). Usually both are the last pair sent; a pid lost on the bus
    // leaves the mixer holding an older one, which goes stale sooner.
    const motor_pwm_t& held = cycles[*failsafe].pwm;
    const auto setpoint_sent = pilot_->send_started(held.setpoint_utime);
    const auto pid_sent = pilot_->send_started(held.pid_utime);
    ASSERT_TRUE(setpoint_sent && pid_sent) << "the failsafe names inputs this test did not send";
    if (held.pid_utime != pilot_->last_utime() || held.setpoint_utime != pilot_->last_utime()) {
      std::cerr << "note: the mixer did not hold the last pair sent (setpoint "
                << held.setpoint_utime << ", pid " << held.pid_utime << ", last "
                << pilot_->last_utime() << ")\n";
    }
    const std::size_t first = cycles[*failsafe].pwm_index;
    const auto after = bus_->pwm_times()[first] - std::min(*setpoint_sent, *pid_sent);
    EXPECT_GE(after, timeout) << "first disarmed output "
                              << std::chrono::duration<double, std::milli>(after).count()
                              << " ms after the held inputs were sent";

    // The publisher comes back still saying "armed": no output until re-armed.
    ASSERT_TRUE(fly_until(true, 0.5, [](const motor_pwm_t& m) { return !m.armed; }));
    for (int k = 0; k < 20; ++k) {
      ASSERT_TRUE(fly_until(true, 0.5, [](const motor_pwm_t&) { return true; }));
      ASSERT_FALSE(bus_->pwm().back().armed) << "motors restarted without a re-arm";
    }
    ASSERT_EQ(bus_->status().back().state, mixer_status_t::STATE_FAILSAFE);
  }
  EXPECT_GE(bus_->status().back().failsafe_events, 5);
  mixer_->signal(SIGTERM);
  EXPECT_EQ(mixer_->wait_for(10s), 0);
}

TEST_F(ProcessSafety, GarbageIsCountedNeverFatalNeverOutOfRange) {
  // Timeouts far above any stall of a loaded machine: this test is about the
  // counters and the range, and a legitimate failsafe would end its flight.
  start({"inputs.setpoint_timeout_ms=2000", "inputs.pid_timeout_ms=2000"});
  arm();
  std::mt19937 rng(99);
  std::uniform_int_distribution<int> byte(0, 255);
  std::uniform_int_distribution<int> length(0, 64);
  constexpr int kRandom = 200;
  for (int k = 0; k < kRandom; ++k) {
    std::vector<std::uint8_t> junk(static_cast<std::size_t>(length(rng)));
    for (auto& b : junk) b = static_cast<std::uint8_t>(byte(rng));
    pilot_->raw(k % 2 ? config_.channels.setpoint : config_.channels.pid, junk);
  }
  // Another type on the setpoint channel, and a truncated setpoint.
  pid_t wrong{};
  pilot_->message(config_.channels.setpoint, wrong);
  setpoint_t sp{};
  sp.utime = wall_us();
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(sp.getEncodedSize()));
  sp.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  bytes.resize(bytes.size() - 3);
  pilot_->raw(config_.channels.setpoint, bytes);
  // Well-formed messages with bad values.
  pid_t nan_pid{};
  nan_pid.utime = wall_us();
  nan_pid.roll = std::numeric_limits<float>::quiet_NaN();
  pilot_->message(config_.channels.pid, nan_pid);
  setpoint_t big{};
  big.utime = wall_us();
  big.throttle = 7.0F;
  big.armed = true;
  pilot_->message(config_.channels.setpoint, big);
  pid_t inf_pid{};
  inf_pid.utime = wall_us();
  inf_pid.pitch = std::numeric_limits<float>::infinity();
  pilot_->message(config_.channels.pid, inf_pid);

  // Keep flying and wait for the counters to show all of it.
  bool counted = false;
  for (int k = 0; k < 300 && !counted; ++k) {
    pilot_->send(true, 0.5, 0.3);
    counted = bus_->wait_until(
        [&](const auto&, const auto& status) {
          if (status.empty()) return false;
          const auto& s = status.back();
          return s.rejected_decode >= kRandom / 2 + 2 && s.rejected_nonfinite >= 2 &&
                 s.rejected_range >= 1;
        },
        5ms);
  }
  EXPECT_TRUE(counted);
  ASSERT_TRUE(mixer_->running()) << "garbage killed the mixer";
  ASSERT_TRUE(fly_until(true, 0.5, [](const motor_pwm_t& m) { return m.armed; }));
  expect_outputs_in_range();
  mixer_->signal(SIGTERM);
  EXPECT_EQ(mixer_->wait_for(10s), 0);
}

TEST_F(ProcessSafety, SigtermInFlightEndsWithADisarmedMessage) {
  start({"inputs.setpoint_timeout_ms=2000", "inputs.pid_timeout_ms=2000"});
  arm();
  ASSERT_TRUE(bus_->pwm().back().armed);
  stop_and_expect_disarmed_exit();
  const auto pwm = bus_->pwm();  // a copy: the loop below must not outlive it
  for (float v : pwm.back().pwm) EXPECT_EQ(v, 1000.0F);
}

// hold_last: from the failsafe cycle on, the last outputs are held while the
// failsafe is at most hold_last_ms old, and every cycle after that is
// disarmed. Measured in the mixer's own clock: the setpoint's age grows by
// exactly the time since the failsafe, as no input arrives.
TEST_F(ProcessSafety, HoldLastKeepsOutputsForABoundedTimeThenDisarms) {
  start({"inputs.failsafe=hold_last", "inputs.hold_last_ms=300", "status_rate_hz=400"});
  const double timeout_ms = config_.inputs.setpoint_timeout_s * 1e3;
  const double hold_ms = 300.0;
  arm();
  const motor_pwm_t flying = bus_->pwm().back();
  const std::size_t from = bus_->status().size();
  // A status this old was published cycles after the disarming one.
  ASSERT_TRUE(bus_->wait_until(
      [&](const auto&, const auto& status) {
        return status.size() > from && status.back().input_age_ms[0] > timeout_ms + hold_ms + 20.0;
      },
      3s));
  const std::vector<CycleRecord> cycles = cycles_since(from);
  const auto failsafe = expect_failsafe_in_first_late_cycle(cycles);
  ASSERT_TRUE(failsafe.has_value());
  const double failed_at_ms = cycles[*failsafe].status.input_age_ms[0];
  int held = 0;
  int disarmed = 0;
  for (std::size_t k = *failsafe; k < cycles.size(); ++k) {
    const double since_ms = cycles[k].status.input_age_ms[0] - failed_at_ms;
    SCOPED_TRACE("cycle " + std::to_string(cycles[k].status.cycles) + ", " +
                 std::to_string(since_ms) + " ms into the failsafe");
    if (since_ms <= hold_ms - kAgeRoundingMs) {
      EXPECT_EQ(cycles[k].pwm.pwm, flying.pwm);  // held: the last outputs, unchanged
      ++held;
    } else if (since_ms > hold_ms + kAgeRoundingMs) {
      EXPECT_FALSE(cycles[k].pwm.armed);
      for (float v : cycles[k].pwm.pwm) EXPECT_EQ(v, 1000.0F);
      ++disarmed;
    }
  }
  EXPECT_GT(held, 0);
  EXPECT_GT(disarmed, 0);
  mixer_->signal(SIGTERM);
  EXPECT_EQ(mixer_->wait_for(10s), 0);
}

// Real-time requests: each one is either granted, as the timing report
// (read back from the kernel) says, or refused with a warning on stderr
// naming it; either way the process carries on flying. Run twice: as the
// test runs (root in the private bus's network namespace: granted), and
// inside a user namespace of its own, where the kernel refuses SCHED_FIFO
// and mlockall: the refusal branch, seen as root too.
TEST_F(ProcessSafety, RealtimeRequestsAreGrantedOrRefusedWithAWarningAndFlyingGoesOn) {
  const bool can_unshare = std::system("unshare -r true >/dev/null 2>&1") == 0;
  for (const bool refused_namespace : {false, true}) {
    if (refused_namespace && !can_unshare) {
      std::cout << "no user namespaces here: the refusal branch is not run\n";
      continue;
    }
    SCOPED_TRACE(refused_namespace ? "in a user namespace" : "as the test runs");
    const std::string dir = ::testing::TempDir();
    const std::string report_path = dir + "/timing_report.json";
    const std::string err_path = dir + "/realtime_stderr.txt";
    std::remove(report_path.c_str());
    start(
        {"realtime.priority=20", "realtime.cpus=[0]", "realtime.lock_memory=true"},
        "config/team_quad.yaml", {"--timing-report", report_path},
        refused_namespace ? std::vector<std::string>{"unshare", "-r"} : std::vector<std::string>{},
        err_path);
    arm();
    EXPECT_TRUE(mixer_->running());
    mixer_->signal(SIGTERM);
    ASSERT_EQ(mixer_->wait_for(10s), 0);
    std::ifstream report_file(report_path);
    ASSERT_TRUE(report_file.good()) << report_path;
    const nlohmann::json report = nlohmann::json::parse(report_file);
    std::ifstream err_file(err_path);
    const std::string err((std::istreambuf_iterator<char>(err_file)), {});
    const auto& rt = report.at("realtime");
    const bool fifo = rt.at("policy") == "SCHED_FIFO" && rt.at("priority") == 20;
    const bool on_cpu0 = rt.at("cpus") == nlohmann::json::array({0});
    const bool locked = rt.at("memory_locked").get<bool>();
    EXPECT_NE(fifo, err.find("SCHED_FIFO priority 20 refused") != std::string::npos) << err;
    EXPECT_NE(on_cpu0, err.find("CPU affinity refused") != std::string::npos) << err;
    EXPECT_NE(locked, err.find("mlockall refused") != std::string::npos) << err;
    if (refused_namespace) {
      EXPECT_FALSE(fifo) << "SCHED_FIFO inside a user namespace";
      EXPECT_EQ(rt.at("policy"), "SCHED_OTHER");
    } else if (geteuid() == 0) {
      EXPECT_TRUE(fifo) << "root in the private bus's namespace is granted SCHED_FIFO";
    }
    // The run's loop timing, consistent with itself.
    const auto& wake = report.at("wake_latency_us");
    EXPECT_GT(report.at("timer_ticks").get<std::int64_t>(), 0);
    EXPECT_GT(wake.at("count").get<std::int64_t>(), 0);
    EXPECT_LE(wake.at("p50").get<double>(), wake.at("p99").get<double>());
    EXPECT_LE(wake.at("p99").get<double>(), wake.at("p999").get<double>());
    EXPECT_LE(wake.at("p999").get<double>(), std::ceil(wake.at("max").get<double>()));
    const auto& period = report.at("period_us");
    EXPECT_GT(period.at("count").get<std::int64_t>(), 0);
    EXPECT_GE(period.at("max").get<double>(), period.at("min").get<double>());
    mixer_.reset();
    bus_.reset();
  }
}

// The loop never runs fast: over two seconds of outputs, the mean period
// between their publication times (the mixer's clock) is at least the
// configured one, less what a late first output can take off (bounded here
// by a tenth). A loop that falls behind on a loaded machine is slower, not
// wrong, and repeats no missed cycle; how close it keeps to its rate, and its
// jitter, are measured in scripts/bench, not asserted here.
TEST_F(ProcessSafety, LoopNeverRunsFast) {
  for (int rate : {400, 2000}) {
    SCOPED_TRACE(std::to_string(rate) + " Hz");
    start({"loop_rate_hz=" + std::to_string(rate)});
    const std::size_t from = bus_->pwm_count();
    const auto count = static_cast<std::size_t>(rate * 2);
    ASSERT_TRUE(bus_->wait_until(
        [&](const auto& pwm, const auto&) { return pwm.size() >= from + count; }, 20s));
    const auto pwm = bus_->pwm();
    const double span_us = static_cast<double>(pwm[from + count - 1].utime - pwm[from].utime);
    const double period_us = 1e6 / rate;
    EXPECT_GE(span_us / static_cast<double>(count - 1), 0.9 * period_us);
    ASSERT_TRUE(bus_->wait_until([](const auto&, const auto& s) { return s.size() >= 3; }, 5s));
    const auto status = bus_->status().back();
    EXPECT_GT(status.period_us[1], 0.0F);  // the period and compute time are reported
    EXPECT_GT(status.compute_us[2], 0.0F);
    mixer_->signal(SIGTERM);
    EXPECT_EQ(mixer_->wait_for(10s), 0);
    mixer_.reset();
    bus_.reset();
  }
}

}  // namespace
}  // namespace motormix::test
