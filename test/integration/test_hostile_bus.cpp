// Every motormix process that reads the bus, fed hostile messages on a
// private bus (hostile_messages.hpp: array lengths -1, 0, 17, 2^31-1,
// truncated, trailing bytes, another fingerprint, empty, NaN/inf/1e30
// values). Each must:
//   - stay up, and answer SIGTERM within 1 s;
//   - keep its pins or outputs disarmed;
//   - count every refusal, by reason, exactly as many as were sent;
//   - still take a good message afterwards.
// Covered: motormix output (sysfs pins in a temporary tree), run, monitor,
// sim --lcm, motor-test and esc-calibrate.

#include "integration/hostile_messages.hpp"
#include "integration/mixer_fixture.hpp"
#include "integration/process.hpp"
#include "integration/sysfs_pwm_tree.hpp"
#include "test_paths.hpp"

#include <motormix/mixer_status_t.hpp>
#include <motormix/motor_pwm_t.hpp>
#include <motormix/motor_status_t.hpp>
#include <motormix/motor_test_t.hpp>
#include <motormix/pid_t.hpp>
#include <motormix/setpoint_t.hpp>

#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>

#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <limits>
#include <mutex>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace motormix::test {
namespace {

using namespace std::chrono_literals;

constexpr auto kSigtermAnswer = 1000ms;  // the bound: exit within 1 s of SIGTERM
constexpr int kRepeats = 3;              // each hostile variant sent this often
constexpr auto kPace = 3ms;              // between messages: no receive queue overflows
constexpr long long kDisarmedNs = 1'000'000;

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The last match of `pattern`'s first group in `text`, as a number (-1: none).
long long last_number(const std::string& text, const std::string& pattern) {
  const std::regex re(pattern);
  long long v = -1;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), re); it != std::sregex_iterator();
       ++it)
    v = std::stoll((*it)[1].str());
  return v;
}

// The refusals a process printed with bus::describe(), last occurrence.
bus::Refusals printed_refusals(const std::string& text) {
  bus::Refusals r;
  const auto n = [&](const char* what) {
    return static_cast<std::uint64_t>(
        std::max(0LL, last_number(text, std::string("(\\d+) ") + what)));
  };
  r.signature = n("signature");
  r.truncated = n("truncated");
  r.trailing = n("trailing bytes");
  r.wrong_type = n("wrong type");
  r.bad_length = n("bad length");
  r.undecodable = n("undecodable");
  return r;
}

// What bus::receive must have counted for `variants` sent kRepeats times.
bus::Refusals expected_refusals(const std::vector<Hostile>& variants) {
  bus::Refusals r;
  for (const Hostile& h : variants)
    for (int i = 0; i < kRepeats; ++i) r.count(h.refusal);
  return r;
}

void expect_same_refusals(const bus::Refusals& got, const bus::Refusals& want,
                          const std::string& who) {
  EXPECT_EQ(got.truncated, want.truncated) << who;
  EXPECT_EQ(got.trailing, want.trailing) << who;
  EXPECT_EQ(got.wrong_type, want.wrong_type) << who;
  EXPECT_EQ(got.bad_length, want.bad_length) << who;
  EXPECT_EQ(got.undecodable, want.undecodable) << who;
  EXPECT_EQ(got.signature, 0u) << who;
}

// SIGTERM answered within kSigtermAnswer: the exit code (nullopt: not in time).
std::optional<int> terminate(ChildProcess& p) {
  p.signal(SIGTERM);
  return p.wait_for(std::chrono::duration_cast<std::chrono::milliseconds>(kSigtermAnswer));
}

motor_pwm_t armed_pwm(float value) {
  motor_pwm_t m{};
  bus::WireShape<motor_pwm_t>::size(m, 4);
  m.utime = wall_us();
  m.pwm.assign(4, value);
  m.command.assign(4, 0.9F);
  m.armed = true;
  return m;
}

mixer_status_t status_of(int motors) {
  mixer_status_t s{};
  s.utime = wall_us();
  s.num_motors = motors;
  s.state = mixer_status_t::STATE_DISARMED;
  return s;
}

class HostileBus : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(in_private_bus()) << "run through scripts/private-bus";
    ASSERT_TRUE(lcm_.good());
    char tmpl[] = "/tmp/motormix-hostile-XXXXXX";
    dir_ = mkdtemp(tmpl);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  void send(const std::string& channel, const std::vector<std::uint8_t>& bytes) {
    lcm_.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
    std::this_thread::sleep_for(kPace);
  }
  // Every variant, kRepeats times; `after` runs after each message.
  void send_all(const std::string& channel, const std::vector<Hostile>& variants,
                const std::function<void(const Hostile&)>& after = {}) {
    for (int k = 0; k < kRepeats; ++k) {
      for (const Hostile& h : variants) {
        send(channel, h.bytes);
        if (after) after(h);
      }
    }
  }
  std::vector<std::string> shell(const std::string& command) {
    return {"/bin/sh", "-c", "exec " + command};
  }

  lcm::LCM lcm_;
  std::string dir_;
};

// ---- motormix output: sysfs pins in a temporary tree ----

TEST_F(HostileBus, OutputKeepsItsPinsDisarmedCountsEveryRefusalAndTakesAGoodMessage) {
  const std::string root = dir_ + "/sys";
  make_sysfs_pwm_tree(root, 4);
  const std::string config = dir_ + "/output.yaml";
  std::ofstream(config) << "geometry: {preset: quad_x}\n"
                           "output: {min: 1000, max: 2000, disarmed: 1000}\n"
                           "hardware: {driver: sysfs, sysfs: {root: "
                        << root << "}}\n";
  const auto duty = [&](int c) { return read_duty(root, c); };
  const auto wait_duty = [&](long long ns, std::chrono::milliseconds bound) {
    return test::wait_duty(root, 0, ns, static_cast<double>(bound.count())) >= 0.0;
  };
  const std::string log = dir_ + "/output.log";
  ChildProcess output({motormix_binary(), "output", "--config", config}, log);
  ASSERT_TRUE(wait_duty(kDisarmedNs, 5000ms)) << read_file(log);
  // Subscribed before that write; LCM's receive thread joins the group a
  // moment later.
  std::this_thread::sleep_for(300ms);

  const auto variants = hostile_variants<motor_pwm_t>(
      armed_pwm(1900.0F), [](motor_pwm_t& m, float v) { m.pwm.assign(m.pwm.size(), v); });
  int moved = 0;
  send_all("MOTOR_PWM", variants, [&](const Hostile&) {
    // Read at once: the pins are written in the callback, before the 50 ms
    // staleness could disarm them again.
    for (int c = 0; c < 4; ++c) moved += duty(c) != kDisarmedNs ? 1 : 0;
  });
  EXPECT_EQ(moved, 0) << "a hostile message moved a pin";
  EXPECT_TRUE(output.running()) << read_file(log);
  EXPECT_EQ(read_file(log).find("-> armed"), std::string::npos) << read_file(log);

  // A good message afterwards is still taken.
  bool taken = false;
  for (int i = 0; i < 200 && !taken; ++i) {
    send("MOTOR_PWM", encode_plain(armed_pwm(1500.0F)));
    taken = duty(0) == 1'500'000;
  }
  EXPECT_TRUE(taken) << read_file(log);

  const auto rc = terminate(output);
  ASSERT_TRUE(rc.has_value()) << "no exit within 1 s of SIGTERM\n" << read_file(log);
  EXPECT_EQ(*rc, 0);
  EXPECT_TRUE(wait_duty(kDisarmedNs, 100ms)) << "not disarmed on exit";
  const std::string text = read_file(log);
  expect_same_refusals(printed_refusals(text), expected_refusals(variants), text);
  // NaN and inf: not finite; 1e30: out of range (never clamped to full thrust).
  EXPECT_EQ(last_number(text, "(\\d+) not finite"), 2 * kRepeats) << text;
  EXPECT_EQ(last_number(text, "(\\d+) out of range"), kRepeats) << text;
}

// ---- motormix run ----

class HostileMixer : public MixerProcessTest {};

TEST_F(HostileMixer, RunStaysDisarmedCountsEveryRefusalAndStillArms) {
  ASSERT_NO_FATAL_FAILURE(start({}, "config/quad_x.yaml"));
  lcm::LCM lcm;
  ASSERT_TRUE(lcm.good());
  const auto send = [&](const std::string& channel, const std::vector<Hostile>& vs) {
    for (int k = 0; k < kRepeats; ++k) {
      for (const Hostile& h : vs) {
        lcm.publish(channel, h.bytes.data(), static_cast<unsigned>(h.bytes.size()));
        std::this_thread::sleep_for(kPace);
      }
    }
  };
  setpoint_t sp{};
  sp.utime = wall_us();
  sp.armed = true;
  const auto setpoints =
      hostile_variants<setpoint_t>(sp, [](setpoint_t& m, float v) { m.throttle = v; });
  pid_t pid{};
  pid.utime = wall_us();
  const auto pids = hostile_variants<pid_t>(pid, [](pid_t& m, float v) { m.roll = v; });
  motor_status_t ms{};
  bus::WireShape<motor_status_t>::size(ms, 4);
  ms.utime = wall_us();
  const auto statuses = hostile_variants<motor_status_t>(ms);
  motor_test_t mt{};
  mt.utime = wall_us();
  mt.motor = 1;
  const auto tests = hostile_variants<motor_test_t>(mt);
  const std::size_t pwm_before = bus_->pwm().size();
  send(config_.channels.setpoint, setpoints);
  send(config_.channels.pid, pids);
  send(config_.channels.motor_status, statuses);
  send(config_.channels.motor_test, tests);
  ASSERT_TRUE(mixer_->running());
  const auto pwm = bus_->pwm();
  for (std::size_t i = pwm_before; i < pwm.size(); ++i)
    ASSERT_FALSE(pwm[i].armed) << "armed output " << i << " during the hostile messages";

  // Every malformed message counted by its reason, as every other process
  // counts it; the poison values (NaN, inf: non-finite; 1e30: out of
  // range) by the loop's checks.
  bus::Refusals expected;
  for (const auto* vs : {&setpoints, &pids, &statuses, &tests}) expected += expected_refusals(*vs);
  const std::uint64_t malformed = expected.malformed();
  ASSERT_TRUE(bus_->wait_until(
      [&](const auto&, const auto& status) {
        return !status.empty() &&
               static_cast<std::uint64_t>(status.back().rejected_decode) >= malformed;
      },
      3s));
  const mixer_status_t last = bus_->status().back();
  EXPECT_EQ(static_cast<std::uint64_t>(last.rejected_decode), malformed);
  const auto counted = [](std::int64_t v) { return static_cast<std::uint64_t>(v); };
  EXPECT_EQ(counted(last.rejected_truncated), expected.truncated);
  EXPECT_EQ(counted(last.rejected_trailing), expected.trailing);
  EXPECT_EQ(counted(last.rejected_wrong_type), expected.wrong_type);
  EXPECT_EQ(counted(last.rejected_bad_length), expected.bad_length);
  EXPECT_EQ(counted(last.rejected_undecodable), expected.undecodable);
  EXPECT_GT(expected.truncated * expected.trailing * expected.wrong_type * expected.bad_length, 0U)
      << "the hostile variants cover every reason";
  EXPECT_EQ(last.rejected_nonfinite, 2 * 2 * kRepeats);  // setpoint and pid, NaN and inf
  EXPECT_EQ(last.rejected_range, 2 * kRepeats);          // 1e30 in each
  EXPECT_EQ(last.setpoint_received, 0);
  EXPECT_EQ(last.motor_tests_started, 0);

  // Good pairs afterwards are taken: disarmed first, then armed.
  EXPECT_TRUE(fly_until(false, 0.0, [](const motor_pwm_t& p) { return !p.armed; }));
  EXPECT_TRUE(fly_until(true, 0.0, [](const motor_pwm_t& p) { return p.armed; }))
      << "state " << int{bus_->status().back().state} << ", failsafe reason "
      << int{bus_->status().back().failsafe_reason} << ", arming refused "
      << bus_->status().back().arming_refused;
  const auto rc = terminate(*mixer_);
  ASSERT_TRUE(rc.has_value()) << "no exit within 1 s of SIGTERM";
  EXPECT_EQ(*rc, 0);
}

// ---- motormix monitor ----

TEST_F(HostileBus, MonitorStaysUpCountsEveryRefusalAndShowsAGoodStatus) {
  const std::string screen = dir_ + "/screen.txt";
  ChildProcess monitor(
      shell(std::string(motormix_binary()) + " monitor --duration 60 --wait 60 > " + screen),
      dir_ + "/monitor.log");
  std::this_thread::sleep_for(300ms);  // subscribed
  auto status_variants = hostile_variants<mixer_status_t>(status_of(4));
  // Whole messages whose motor count no mixer has: one row per motor.
  for (const int n : {-1, 0, 17, std::numeric_limits<std::int32_t>::max()})
    status_variants.push_back(
        {"num_motors " + std::to_string(n), encode_plain(status_of(n)), bus::Refusal::kBadLength});
  const auto pwm_variants = hostile_variants<motor_pwm_t>(armed_pwm(1500.0F));
  send_all("MIXER_STATUS", status_variants);
  send_all("MOTOR_PWM", pwm_variants);
  EXPECT_TRUE(monitor.running()) << read_file(dir_ + "/monitor.log");

  bool shown = false;
  for (int i = 0; i < 300 && !shown; ++i) {
    send("MIXER_STATUS", encode_plain(status_of(4)));
    send("MOTOR_PWM", encode_plain(armed_pwm(1500.0F)));
    shown = read_file(screen).find(" refused: ") != std::string::npos;
  }
  ASSERT_TRUE(shown) << read_file(screen);
  std::this_thread::sleep_for(300ms);  // one more redraw with the final counts
  const auto rc = terminate(monitor);
  ASSERT_TRUE(rc.has_value()) << "no exit within 1 s of SIGTERM";
  EXPECT_EQ(*rc, 0);
  bus::Refusals want = expected_refusals(status_variants);
  want += expected_refusals(pwm_variants);
  const std::string text = read_file(screen);
  const std::string last = text.substr(text.rfind("monitor   "));
  expect_same_refusals(printed_refusals(last), want, last);
}

// ---- motormix sim --lcm ----

TEST_F(HostileBus, LiveSimStaysUpCountsEveryRefusalAndTakesAGoodOutput) {
  const std::string out = dir_ + "/sim.json";
  ChildProcess sim(
      shell(std::string(motormix_binary()) + " sim --lcm --config " +
            source_path("config/quad_x.yaml") + " --scenario hover --duration 60 --json > " + out),
      dir_ + "/sim.log");
  std::this_thread::sleep_for(500ms);  // subscribed
  const auto pwm_variants = hostile_variants<motor_pwm_t>(
      armed_pwm(1900.0F), [](motor_pwm_t& m, float v) { m.pwm.assign(m.pwm.size(), v); });
  const auto status_variants = hostile_variants<mixer_status_t>(status_of(4));
  send_all("MOTOR_PWM", pwm_variants);
  send_all("MIXER_STATUS", status_variants);
  EXPECT_TRUE(sim.running()) << read_file(dir_ + "/sim.log");
  motor_pwm_t good = armed_pwm(1000.0F);  // armed at the bottom of the range: nothing lifts
  for (int i = 0; i < 10; ++i) send("MOTOR_PWM", encode_plain(good));
  const auto rc = terminate(sim);
  ASSERT_TRUE(rc.has_value()) << "no exit within 1 s of SIGTERM\n" << read_file(dir_ + "/sim.log");
  const auto j = nlohmann::json::parse(read_file(out));
  EXPECT_TRUE(j["interrupted"].get<bool>());
  EXPECT_FALSE(j["crashed"].get<bool>());
  EXPECT_GE(j["pwm_received"].get<long>(), 5) << "good outputs not taken";
  bus::Refusals want = expected_refusals(pwm_variants);
  want += expected_refusals(status_variants);
  EXPECT_EQ(j["refused"]["truncated"].get<std::uint64_t>(), want.truncated) << j.dump();
  EXPECT_EQ(j["refused"]["trailing"].get<std::uint64_t>(), want.trailing) << j.dump();
  EXPECT_EQ(j["refused"]["wrong_type"].get<std::uint64_t>(), want.wrong_type) << j.dump();
  EXPECT_EQ(j["refused"]["bad_length"].get<std::uint64_t>(), want.bad_length) << j.dump();
  // The guard's refusals, plus NaN and inf (not finite) and 1e30... which the
  // simulated ESCs clamp: only the non-finite ones are refused by value.
  EXPECT_EQ(j["pwm_rejected"].get<std::uint64_t>(),
            expected_refusals(pwm_variants).refused() + 2 * kRepeats)
      << j.dump();
}

// ---- motormix motor-test ----

TEST_F(HostileBus, MotorTestIgnoresHostileStatusesTakesTheMixersAnswerAndStopsOnSigterm) {
  const std::string err = dir_ + "/motor-test.log";
  const std::string outp = dir_ + "/motor-test.out";
  ChildProcess client(
      shell(std::string(motormix_binary()) + " motor-test --config " +
            source_path("config/quad_x.yaml") + " --motor 1 --seconds 30 --wait 30 > " + outp),
      err);
  // The request it sends, to answer like a mixer would.
  struct Requests {
    std::mutex m;
    std::int64_t utime = 0;
    void on(const lcm::ReceiveBuffer* rbuf, const std::string&) {
      motor_test_t t;
      if (t.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) > 0 && t.motor > 0) {
        std::lock_guard<std::mutex> lock(m);
        utime = t.utime;
      }
    }
  } requests;
  lcm_.subscribe("MOTOR_TEST", &Requests::on, &requests);
  // Its first request says it listens.
  for (int i = 0; i < 1000; ++i) {
    lcm_.handleTimeout(5);
    std::lock_guard<std::mutex> lock(requests.m);
    if (requests.utime != 0) break;
  }
  const auto variants = hostile_variants<mixer_status_t>(status_of(4));
  send_all("MIXER_STATUS", variants);
  EXPECT_TRUE(client.running()) << read_file(err);
  bool spinning = false;
  for (int i = 0; i < 300 && !spinning; ++i) {
    lcm_.handleTimeout(5);
    std::int64_t utime = 0;
    {
      std::lock_guard<std::mutex> lock(requests.m);
      utime = requests.utime;
    }
    if (utime == 0) continue;
    mixer_status_t s = status_of(4);
    s.motor_test_request_utime = utime;
    s.motor_test_state = mixer_status_t::MOTOR_TEST_RUNNING;
    s.motor_test_motor = 1;
    send("MIXER_STATUS", encode_plain(s));
    spinning = read_file(outp).find("spinning") != std::string::npos;
  }
  EXPECT_TRUE(spinning) << "the mixer's answer was not taken\n" << read_file(err);
  const auto rc = terminate(client);
  ASSERT_TRUE(rc.has_value()) << "no exit within 1 s of SIGTERM\n" << read_file(err);
  const std::string text = read_file(err);
  EXPECT_NE(text.find("interrupted, test stopped"), std::string::npos) << text;
  expect_same_refusals(printed_refusals(text), expected_refusals(variants), text);
}

// ---- motormix esc-calibrate ----

TEST_F(HostileBus, EscCalibrationIsNotFooledByHostileStatusesAndDisarmsOnSigterm) {
  const std::string err = dir_ + "/esc.log";
  const std::string outp = dir_ + "/esc.out";
  struct LastPwm {
    std::mutex m;
    int count = 0;
    bool armed = true;
    void on(const lcm::ReceiveBuffer* rbuf, const std::string&) {
      motor_pwm_t p;
      if (p.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) > 0) {
        std::lock_guard<std::mutex> lock(m);
        ++count;
        armed = p.armed;
      }
    }
  } last;
  lcm_.subscribe("MOTOR_PWM", &LastPwm::on, &last);
  ChildProcess client(shell(std::string(motormix_binary()) + " esc-calibrate --config " +
                            source_path("config/quad_x.yaml") + " --props-off --timeout 60 > " +
                            outp + " < /dev/null"),
                      err);
  // While it listens for a mixer (its first second): hostile statuses
  // are no status. Its subscription is up once it publishes nothing for
  // 300 ms; a late start shows as too few refusals, not a pass.
  std::this_thread::sleep_for(300ms);
  const auto variants = hostile_variants<mixer_status_t>(status_of(4));
  send_all("MIXER_STATUS", variants);
  bool at_maximum = false;
  for (int i = 0; i < 500 && !at_maximum; ++i) {
    std::this_thread::sleep_for(10ms);
    at_maximum = read_file(outp).find("at its maximum") != std::string::npos;
  }
  // (stdin at its end aborts the maximum phase at once: it must not have
  // been reached with a status believed, and it ends disarmed.)
  const auto rc = client.wait_for(5000ms);
  ASSERT_TRUE(rc.has_value()) << read_file(err);
  for (int i = 0; i < 50; ++i) lcm_.handleTimeout(10);
  std::string text = read_file(err);
  EXPECT_TRUE(at_maximum) << "a hostile status stopped the calibration\n" << text;
  expect_same_refusals(printed_refusals(text), expected_refusals(variants), text);
  {
    std::lock_guard<std::mutex> lock(last.m);
    EXPECT_GT(last.count, 0);
    EXPECT_FALSE(last.armed) << "its last output was not disarmed";
  }

  // A good status while it listens is taken: a mixer runs, nothing is sent.
  ChildProcess second(shell(std::string(motormix_binary()) + " esc-calibrate --config " +
                            source_path("config/quad_x.yaml") + " --props-off --timeout 60 > " +
                            outp + " < /dev/null"),
                      err);
  // A status every 20 ms until it answers (bounded): a child slow to start
  // (the sanitizers) subscribes after a burst sent at once has gone by.
  for (int i = 0; i < 250 && second.running(); ++i) {
    send("MIXER_STATUS", encode_plain(status_of(4)));
    std::this_thread::sleep_for(20ms);
  }
  const auto rc2 = second.wait_for(5000ms);
  ASSERT_TRUE(rc2.has_value());
  EXPECT_NE(read_file(err).find("a mixer is running"), std::string::npos) << read_file(err);

  // SIGTERM while it holds the maximum, its stdin open (a FIFO this test
  // holds): answered within 1 s.
  const std::string fifo = dir_ + "/stdin";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  ChildProcess third(shell(std::string(motormix_binary()) + " esc-calibrate --config " +
                           source_path("config/quad_x.yaml") + " --props-off --timeout 60 > " +
                           outp + " < " + fifo),
                     err);
  const int stdin_fd = ::open(fifo.c_str(), O_WRONLY);  // until the child opens its end
  ASSERT_GE(stdin_fd, 0);
  at_maximum = false;
  for (int i = 0; i < 500 && !at_maximum; ++i) {
    std::this_thread::sleep_for(10ms);
    at_maximum = read_file(outp).find("at its maximum") != std::string::npos;
  }
  EXPECT_TRUE(at_maximum) << read_file(err);
  const auto rc3 = terminate(third);
  ::close(stdin_fd);
  EXPECT_TRUE(rc3.has_value()) << "no exit within 1 s of SIGTERM\n" << read_file(err);
  for (int i = 0; i < 50; ++i) lcm_.handleTimeout(10);
  std::lock_guard<std::mutex> lock(last.m);
  EXPECT_FALSE(last.armed) << "its last output was not disarmed";
}

}  // namespace
}  // namespace motormix::test
