// `motormix run` as a process on a private bus: the publisher goes away and
// comes back, garbage arrives, SIGTERM arrives mid-flight, and the loop keeps
// its rate. Every wait is on messages, with a bounded timeout; every loop is
// bounded in count.

#include "integration/mixer_fixture.hpp"

#include <algorithm>
#include <csignal>
#include <cstdlib>
#include <random>
#include <thread>

namespace motormix::test {
namespace {

class ProcessSafety : public MixerProcessTest {};

TEST_F(ProcessSafety, PublisherDropoutFailsSafeWithinTimeoutPlusOnePeriod) {
  start();
  const auto timeout =
      std::chrono::milliseconds(static_cast<int>(config_.inputs.setpoint_timeout_s * 1e3));
  const auto period = std::chrono::microseconds(static_cast<int>(1e6 / config_.loop_rate_hz));
  for (int trial = 0; trial < 5; ++trial) {
    SCOPED_TRACE("trial " + std::to_string(trial));
    arm();
    const Clock::time_point stopped = pilot_->last_sent;
    const std::size_t before = bus_->pwm_count();
    const auto found = first_disarmed_after(before, 2s);
    ASSERT_TRUE(found.has_value());
    const std::size_t first = *found;
    const auto pwm = bus_->pwm();
    const auto times = bus_->pwm_times();
    const auto took = times[first] - stopped;
    EXPECT_LE(took, timeout + period + kTransportSlack)
        << std::chrono::duration_cast<std::chrono::microseconds>(took).count() << " us";
    EXPECT_GE(took, timeout - 5ms);  // and not before the timeout
    for (int i = 0; i < 4; ++i) EXPECT_EQ(pwm[first].pwm[static_cast<std::size_t>(i)], 1000.0F);

    // The publisher comes back still saying "armed": no output until re-armed.
    ASSERT_TRUE(fly_until(true, 0.5, [](const motor_pwm_t& m) { return !m.armed; }));
    for (int k = 0; k < 20; ++k) {
      ASSERT_TRUE(fly_until(true, 0.5, [](const motor_pwm_t&) { return true; }));
      ASSERT_FALSE(bus_->pwm().back().armed) << "motors restarted without a re-arm";
    }
    ASSERT_TRUE(bus_->wait_until(
        [](const auto&, const auto& status) {
          return !status.empty() && status.back().state == mixer_status_t::STATE_FAILSAFE;
        },
        2s));
  }
  EXPECT_GE(bus_->status().back().failsafe_events, 5);
  mixer_->signal(SIGTERM);
  EXPECT_EQ(mixer_->wait_for(10s), 0);
}

TEST_F(ProcessSafety, GarbageIsCountedNeverFatalNeverOutOfRange) {
  start();
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

TEST_F(ProcessSafety, HoldLastKeepsOutputsForABoundedTimeThenDisarms) {
  start({"inputs.failsafe=hold_last", "inputs.hold_last_ms=300"});
  const auto timeout = std::chrono::milliseconds(100);
  const auto hold = std::chrono::milliseconds(300);
  const auto period = std::chrono::microseconds(static_cast<int>(1e6 / config_.loop_rate_hz));
  arm();
  const motor_pwm_t flying = bus_->pwm().back();
  const Clock::time_point stopped = pilot_->last_sent;
  const std::size_t before = bus_->pwm_count();
  const auto found = first_disarmed_after(before, 3s);
  ASSERT_TRUE(found.has_value());
  const std::size_t first = *found;
  const auto pwm = bus_->pwm();
  const auto times = bus_->pwm_times();
  for (std::size_t i = before; i < first; ++i) {
    ASSERT_EQ(pwm[i].pwm, flying.pwm);  // held: the last outputs, unchanged
  }
  const auto took = times[first] - stopped;
  EXPECT_GE(took, timeout + hold - 5ms);
  EXPECT_LE(took, timeout + hold + period + kTransportSlack)
      << std::chrono::duration_cast<std::chrono::microseconds>(took).count() << " us";
  mixer_->signal(SIGTERM);
  EXPECT_EQ(mixer_->wait_for(10s), 0);
}

// Real-time requests the system refuses (no CAP_SYS_NICE inside the test's
// namespace, mlockall over RLIMIT_MEMLOCK) are logged as warnings on stderr,
// and the process carries on flying.
TEST_F(ProcessSafety, RefusedRealtimeRequestsDoNotStopTheProcess) {
  start({"realtime.priority=20", "realtime.cpus=[0]", "realtime.lock_memory=true"});
  arm();
  EXPECT_TRUE(mixer_->running());
  mixer_->signal(SIGTERM);
  EXPECT_EQ(mixer_->wait_for(10s), 0);
}

// How much further behind than an optimized build the loop may fall on a
// loaded machine: 1, or MOTORMIX_LOOP_SLACK where every cycle is several
// times slower (the sanitizer build sets 2: its mean period at 2000 Hz was
// seen at 1.62x the nominal one while CI ran).
double loop_slack() {
  const char* env = std::getenv("MOTORMIX_LOOP_SLACK");
  return env ? std::max(1.0, std::atof(env)) : 1.0;
}

// Generous bounds: tight numbers belong to the benchmarks.
TEST_F(ProcessSafety, LoopKeepsItsRate) {
  const double slack = loop_slack();
  for (int rate : {400, 2000}) {
    SCOPED_TRACE(std::to_string(rate) + " Hz");
    start({"loop_rate_hz=" + std::to_string(rate)});
    const std::size_t from = bus_->pwm_count();
    const auto t0 = Clock::now();
    ASSERT_TRUE(bus_->wait_until(
        [&](const auto& pwm, const auto&) {
          return pwm.size() >= from + static_cast<std::size_t>(rate * 2);
        },
        10s));
    const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    const double measured = static_cast<double>(rate * 2) / seconds;
    // Generous: a loaded two-core machine delays wake-ups, and the loop does
    // not run missed cycles back to back (they would only repeat stale
    // inputs). It must never run fast, and never fall far behind.
    EXPECT_LE(measured, 1.05 * rate);  // never fast, whatever the build
    EXPECT_GE(measured, 0.6 * rate / slack);
    ASSERT_TRUE(bus_->wait_until([](const auto&, const auto& s) { return s.size() >= 3; }, 5s));
    const auto status = bus_->status().back();
    EXPECT_GE(status.period_us[1], 0.95 * 1e6 / rate);  // mean period
    EXPECT_LE(status.period_us[1], 1.6 * slack * 1e6 / rate);
    EXPECT_GT(status.compute_us[2], 0.0F);
    mixer_->signal(SIGTERM);
    EXPECT_EQ(mixer_->wait_for(10s), 0);
    mixer_.reset();
    bus_.reset();
  }
}

}  // namespace
}  // namespace motormix::test
