#pragma once
// A `motormix run` child on the private bus, a pilot that publishes inputs
// like a flight controller, and a recorder of everything the mixer
// publishes. Every wait is on messages, with a bounded timeout; every loop is
// bounded in count.

#include "integration/bus_recorder.hpp"
#include "integration/process.hpp"
#include "test_support.hpp"

#include <motormix/mixer_status_t.hpp>
#include <motormix/motor_pwm_t.hpp>
#include <motormix/pid_t.hpp>
#include <motormix/setpoint_t.hpp>
#include <motormix/signing_policy.hpp>

#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace motormix::test {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

// Input ages travel as float milliseconds: a few 1e-5 ms of rounding at the
// ages of these tests, far below this.
constexpr double kAgeRoundingMs = 0.01;

// One loop cycle as the mixer published it: its status and its outputs.
struct CycleRecord {
  mixer_status_t status;
  motor_pwm_t pwm;
  std::size_t pwm_index;  // where those outputs stand in BusRecorder::pwm()
};

inline std::int64_t wall_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

inline bool in_private_bus() {
  const char* flag = std::getenv("MOTORMIX_PRIVATE_BUS");
  return flag != nullptr && std::string(flag) == "1";
}

// The test side of the bus: publishes inputs like a flight controller would.
class Pilot {
 public:
  explicit Pilot(const config::Config& c) : c_(c) {}
  bool good() { return lcm_.good(); }

  // From now on every message is signed by `policy` (a controller with the
  // key, or one with another key).
  void sign_with(signing::Policy policy) { policy_ = std::move(policy); }

  void send(bool armed, double throttle, double roll = 0.0) {
    // Taken before the pair is published: no receiver can hold either message
    // earlier. (A time taken after publishing is late by however long this
    // thread was preempted in between.)
    const Clock::time_point started = Clock::now();
    setpoint_t sp{};
    sp.utime = wall_us();
    sp.throttle = static_cast<float>(throttle);
    sp.armed = armed;
    message(c_.channels.setpoint, sp);
    pid_t pid{};
    pid.utime = sp.utime;
    pid.roll = static_cast<float>(roll);
    message(c_.channels.pid, pid);
    sent_[next_sent_++ % sent_.size()] = {sp.utime, started};
  }
  // The utime of the last pair sent (0 before the first).
  std::int64_t last_utime() const {
    return sent_[(next_sent_ + sent_.size() - 1) % sent_.size()].utime;
  }
  // When the pair stamped `utime` began to be sent, if it is among the
  // last sends remembered.
  std::optional<Clock::time_point> send_started(std::int64_t utime) const {
    for (const auto& s : sent_) {
      if (s.utime == utime) return s.started;
    }
    return std::nullopt;
  }
  void raw(const std::string& channel, const std::vector<std::uint8_t>& bytes) {
    lcm_.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
  }
  // Publishes m (signed when sign_with() was called); returns the bytes sent.
  template <typename Message>
  std::vector<std::uint8_t> message(const std::string& channel, const Message& m) {
    std::vector<std::uint8_t> bytes;
    bytes.resize(signing::encode_sealed(policy_, channel, m, bytes, wall_us()));
    raw(channel, bytes);
    return bytes;
  }

 private:
  struct Sent {
    std::int64_t utime = 0;
    Clock::time_point started;
  };
  const config::Config& c_;
  signing::Policy policy_;  // off unless sign_with()
  std::array<Sent, 64> sent_{};
  std::size_t next_sent_ = 0;
  lcm::LCM lcm_;
};

class MixerProcessTest : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_TRUE(in_private_bus()) << "run through scripts/private-bus"; }

  // `run_options`: further options of `motormix run` (e.g. --lcm-url).
  void start(const std::vector<std::string>& test_overrides = {},
             const std::string& config_file = "config/team_quad.yaml",
             const std::vector<std::string>& run_options = {},
             const std::vector<std::string>& wrapper = {}, const std::string& stderr_path = "") {
    // These tests check the outputs from the first armed cycle on: no
    // spool-up ramp unless a test asks for one (it has tests of its own).
    std::vector<std::string> overrides = {"output.spool_up_s=0"};
    overrides.insert(overrides.end(), test_overrides.begin(), test_overrides.end());
    config_ = config::load_config_file(source_path(config_file), overrides);
    bus_ = std::make_unique<BusRecorder>(config_.channels.motor_pwm, config_.channels.status, true,
                                         recorder_key_);
    pilot_ = std::make_unique<Pilot>(config_);
    // wrapper: a command the mixer runs under (e.g. `unshare -r`).
    std::vector<std::string> argv = wrapper;
    for (const std::string& a : {std::string(motormix_binary()), std::string("run"),
                                 std::string("--config"), source_path(config_file)}) {
      argv.push_back(a);
    }
    for (const auto& o : overrides) {
      argv.push_back("--set");
      argv.push_back(o);
    }
    argv.insert(argv.end(), run_options.begin(), run_options.end());
    mixer_ = std::make_unique<ChildProcess>(argv, stderr_path);
    ASSERT_TRUE(bus_->wait_until([](const auto& pwm, const auto&) { return !pwm.empty(); }, 10s));
  }

  // Publishes at 200 Hz (bounded count) until an output names the last input
  // and satisfies `want`.
  bool fly_until(bool armed, double throttle, const std::function<bool(const motor_pwm_t&)>& want,
                 int max_sends = 400) {
    for (int k = 0; k < max_sends; ++k) {
      pilot_->send(armed, throttle);
      const std::int64_t sent = pilot_->last_utime();
      if (bus_->wait_until(
              [&](const auto& pwm, const auto&) {
                return !pwm.empty() && pwm.back().setpoint_utime == sent && want(pwm.back());
              },
              5ms)) {
        return true;
      }
    }
    return false;
  }

  // Index of the first disarmed output published after output `before`, once
  // it has arrived (bounded wait); nullopt if none came in time.
  std::optional<std::size_t> first_disarmed_after(std::size_t before,
                                                  std::chrono::milliseconds timeout) {
    std::optional<std::size_t> first;
    bus_->wait_until(
        [&](const auto& pwm, const auto&) {
          for (std::size_t i = before; i < pwm.size(); ++i) {
            if (!pwm[i].armed) {
              first = i;
              return true;
            }
          }
          return false;
        },
        timeout);
    return first;
  }

  // The cycles from status `from` on, each paired with its outputs. Needs a
  // status every cycle (status_rate_hz = loop_rate_hz); a cycle missing from
  // the record (a lost message) fails the test rather than pairing a status
  // with another cycle's outputs.
  std::vector<CycleRecord> cycles_since(std::size_t from) {
    const auto status = bus_->status();
    const auto pwm = bus_->pwm();
    const auto pwm_before = bus_->pwm_before_status();
    std::vector<CycleRecord> cycles;
    for (std::size_t k = from; k < status.size(); ++k) {
      if (k > from && (status[k].cycles != status[k - 1].cycles + 1 ||
                       pwm_before[k] != pwm_before[k - 1] + 1)) {
        ADD_FAILURE() << "cycle " << status[k - 1].cycles + 1 << " missing from the record";
        break;
      }
      if (pwm_before[k] == 0) continue;  // not a cycle's status: nothing before it
      cycles.push_back({status[k], pwm[pwm_before[k] - 1], pwm_before[k] - 1});
    }
    return cycles;
  }

  // Waits (bounded) until a status after status `from` reports the failsafe.
  bool wait_for_failsafe_status(std::size_t from) {
    return bus_->wait_until(
        [&](const auto&, const auto& status) {
          return status.size() > from && status.back().state == mixer_status_t::STATE_FAILSAFE;
        },
        2s);
  }

  // The failsafe checked in the mixer's own clock, from a record of every
  // cycle: each cycle before it flew on a setpoint and a pid younger than
  // their timeouts, and it is the first cycle in which one was older (or in
  // which the loop had stalled past a timeout). So the failsafe comes within
  // one period of the timeout, as the mixer measures both; no bound here
  // depends on how fast this machine runs (the wall-clock latency is in
  // scripts/bench). What the failsafe cycle outputs (disarmed, held, idle)
  // is the caller's to check. Returns its index in `cycles`.
  std::optional<std::size_t> expect_failsafe_in_first_late_cycle(
      const std::vector<CycleRecord>& cycles) {
    const double setpoint_timeout_ms = config_.inputs.setpoint_timeout_s * 1e3;
    const double pid_timeout_ms = config_.inputs.pid_timeout_s * 1e3;
    for (std::size_t k = 0; k < cycles.size(); ++k) {
      const mixer_status_t& s = cycles[k].status;
      if (s.state == mixer_status_t::STATE_ARMED) {
        EXPECT_TRUE(cycles[k].pwm.armed) << "cycle " << s.cycles;
        EXPECT_LE(s.input_age_ms[0], setpoint_timeout_ms + kAgeRoundingMs) << "cycle " << s.cycles;
        EXPECT_LE(s.input_age_ms[1], pid_timeout_ms + kAgeRoundingMs) << "cycle " << s.cycles;
        continue;
      }
      if (s.state != mixer_status_t::STATE_FAILSAFE) continue;
      if (k == 0 || cycles[k - 1].status.state != mixer_status_t::STATE_ARMED) {
        ADD_FAILURE() << "no armed cycle recorded before the failsafe in cycle " << s.cycles;
        return std::nullopt;
      }
      switch (s.failsafe_reason) {
        case mixer_status_t::REASON_SETPOINT_STALE:
          EXPECT_GT(s.input_age_ms[0], setpoint_timeout_ms - kAgeRoundingMs);
          break;
        case mixer_status_t::REASON_PID_STALE:
          EXPECT_GT(s.input_age_ms[1], pid_timeout_ms - kAgeRoundingMs);
          break;
        case mixer_status_t::REASON_LOOP_STALLED:
          break;  // a starved loop: documented, and safe the same way
        default:
          ADD_FAILURE() << "failsafe reason " << int{s.failsafe_reason} << " in cycle " << s.cycles;
      }
      return k;
    }
    ADD_FAILURE() << "no failsafe in " << cycles.size() << " recorded cycles";
    return std::nullopt;
  }

  // Every output so far: finite, in range when armed, the disarmed value otherwise.
  void expect_outputs_in_range() {
    for (const auto& m : bus_->pwm()) {
      for (float v : m.pwm) {
        ASSERT_TRUE(std::isfinite(v));
        // The team quad's range and disarmed value (config/team_quad.yaml).
        ASSERT_TRUE(m.armed ? (v >= 1150.0F && v <= 1924.0F) : v == 1000.0F) << v;
      }
    }
  }
  // SIGTERM: exit 0, and the last word on the bus is disarmed.
  void stop_and_expect_disarmed_exit() {
    // Only a status published after the signal can be the final one: the
    // status runs at 10 Hz, so the newest before the signal may still be a
    // disarmed one from before arming.
    const std::size_t statuses_before = bus_->status().size();
    mixer_->signal(SIGTERM);
    ASSERT_EQ(mixer_->wait_for(10s), 0);
    // Its final status follows its final outputs on the same socket: once it
    // is here, so are they.
    ASSERT_TRUE(bus_->wait_until(
        [&](const auto&, const auto& s) {
          return s.size() > statuses_before && s.back().state == mixer_status_t::STATE_DISARMED;
        },
        5s));
    EXPECT_FALSE(bus_->pwm().back().armed);
  }

  void arm() {
    ASSERT_TRUE(fly_until(false, 0.0, [](const motor_pwm_t& m) { return !m.armed; }));
    ASSERT_TRUE(fly_until(true, 0.0, [](const motor_pwm_t& m) { return m.armed; }));
    ASSERT_TRUE(fly_until(true, 0.5, [](const motor_pwm_t& m) { return m.armed; }));
  }

  config::Config config_;
  // Set before start(): the recorder verifies every output with this key.
  const signing::Key* recorder_key_ = nullptr;
  std::unique_ptr<BusRecorder> bus_;
  std::unique_ptr<Pilot> pilot_;
  std::unique_ptr<ChildProcess> mixer_;
};

}  // namespace motormix::test
