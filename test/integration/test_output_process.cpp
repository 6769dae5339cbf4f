// `motormix output` as a process, on a private bus, with its sysfs driver
// on a PWM tree in a temporary directory (the duty cycles are files to
// read) and an ESC telemetry wire on a pseudo-terminal:
// - disarmed at start; armed values pass, clamped into range; a message with
//   a NaN is refused; armed=false disarms; a silent publisher disarms after
//   the 50 ms timeout; SIGTERM disarms and exits 0;
// - with DShot, two ESCs' KISS telemetry wires are asked in turn and each
//   answer (a third of them corrupted) comes out as esc_telemetry_t for its
//   motor, every good one and no bad one;
// - under security.mode require, only a motor_pwm_t signed with the key
//   moves a pin: unsigned, forged and replayed ones are refused and counted;
// - output_status_t says what the pins carry (starting, armed, disarmed,
//   stale) and counts what was taken and refused, by reason;
// - with the serial driver, a device that goes away (the pseudo-terminal's
//   other end closed) is reopened when it comes back, and the firmware is
//   configured again before the first pulses.

#include "integration/process.hpp"
#include "integration/sysfs_pwm_tree.hpp"
#include "kiss_esc_frame.hpp"
#include "motormix_link.h"
#include "output/kiss_telemetry.hpp"
#include "test_paths.hpp"

#include <motormix/esc_command_t.hpp>
#include <motormix/esc_telemetry_t.hpp>
#include <motormix/motor_pwm_t.hpp>
#include <motormix/output_status_t.hpp>
#include <motormix/signing_policy.hpp>

#include <lcm/lcm-cpp.hpp>

#include <gtest/gtest.h>

#include <fcntl.h>
#include <unistd.h>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <limits>
#include <mutex>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <vector>

namespace motormix::test {
namespace {

using namespace std::chrono_literals;

constexpr double kStaleBoundMs = 50.0 + 15.0;  // the timeout, its 5 ms tick, scheduling
constexpr double kApplyBoundMs = 500.0;        // a value reaching the file, on a loaded machine

// Stops and joins a receiver thread when the test leaves its scope, failed
// assertions included.
struct JoinOnExit {
  std::atomic<bool>* stop;
  std::thread* t;
  ~JoinOnExit() {
    *stop = true;
    if (t->joinable()) t->join();
  }
};

class OutputProcess : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/motormix-output-XXXXXX";
    root_ = mkdtemp(tmpl);
    make_sysfs_pwm_tree(root_, 4);
    master_ = posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK);
    ASSERT_GE(master_, 0);
    grantpt(master_);
    unlockpt(master_);
    char name[128];
    ptsname_r(master_, name, sizeof name);
    config_ = root_ + "/config.yaml";
    std::ofstream(config_) << "geometry: {preset: quad_x}\n"
                              "output: {min: 1000, max: 2000, disarmed: 1000}\n"
                              "hardware:\n"
                              "  driver: sysfs\n"
                              "  sysfs: {root: "
                           << root_ << "}\n";
    wire_ = name;  // an ESC's KISS telemetry wire, for the DShot tests
  }
  void TearDown() override {
    ::close(master_);
    std::filesystem::remove_all(root_);
  }
  long long duty(int c) { return read_duty(root_, c); }
  double wait_duty(int c, long long ns, double bound_ms) {
    return test::wait_duty(root_, c, ns, bound_ms);
  }
  // The bytes of a motor_pwm_t, signed by `policy` unless it is off.
  static std::vector<std::uint8_t> encoded(std::vector<float> pwm, bool armed,
                                           signing::Policy& policy) {
    motormix::motor_pwm_t m{};
    m.num_motors = static_cast<std::int32_t>(pwm.size());
    m.pwm = std::move(pwm);
    m.command.assign(m.pwm.size(), 0.5f);
    m.direction.assign(m.pwm.size(), 0);
    m.armed = armed;
    const auto now = std::chrono::duration_cast<std::chrono::microseconds>(
                         std::chrono::system_clock::now().time_since_epoch())
                         .count();
    std::vector<std::uint8_t> bytes;
    bytes.resize(signing::encode_sealed(policy, "MOTOR_PWM", m, bytes, now));
    return bytes;
  }
  static void send(lcm::LCM& lcm, const std::vector<std::uint8_t>& bytes) {
    lcm.publish("MOTOR_PWM", bytes.data(), static_cast<unsigned>(bytes.size()));
  }
  void publish(lcm::LCM& lcm, std::vector<float> pwm, bool armed) {
    signing::Policy unsigned_policy;
    send(lcm, encoded(std::move(pwm), armed, unsigned_policy));
  }

  std::string root_, config_;
  std::string wire_;  // the slave side of master_
  int master_ = -1;
};

TEST_F(OutputProcess, FailsafeChainOverSysfs) {
  ChildProcess output({motormix_binary(), "output", "--config", config_}, root_ + "/output.log");
  lcm::LCM lcm;
  ASSERT_TRUE(lcm.good());
  ASSERT_GE(wait_duty(0, 1000000, 3000), 0.0) << "no disarmed duty at start";
  std::this_thread::sleep_for(100ms);
  EXPECT_EQ(duty(3), 1000000);

  // Armed, one value beyond the range: clamped.
  for (int i = 0; i < 20; ++i) {
    publish(lcm, {1500, 1600, 2500, 1234.5f}, true);
    std::this_thread::sleep_for(2500us);
  }
  EXPECT_GE(wait_duty(3, 1234500, kApplyBoundMs), 0.0);
  EXPECT_EQ(duty(0), 1500000);
  EXPECT_EQ(duty(2), 2000000);
  // A NaN: refused, nothing changes while good ones keep coming (the good
  // one after it is 1601 on motor 2: when that is written, the NaN message
  // has been dealt with).
  publish(lcm, {std::numeric_limits<float>::quiet_NaN(), 1900, 1900, 1900}, true);
  publish(lcm, {1500, 1601, 2500, 1234.5f}, true);
  EXPECT_GE(wait_duty(1, 1601000, kApplyBoundMs), 0.0);
  EXPECT_EQ(duty(0), 1500000);
  // armed=false: disarmed.
  publish(lcm, {1500, 1600, 1700, 1800}, false);
  EXPECT_GE(wait_duty(1, 1000000, kApplyBoundMs), 0.0);
  // Armed again, then the publisher goes quiet: disarmed after the timeout.
  const auto last_publish = std::chrono::steady_clock::now();
  publish(lcm, {1700, 1700, 1700, 1700}, true);
  ASSERT_GE(wait_duty(0, 1700000, kApplyBoundMs), 0.0);
  ASSERT_GE(wait_duty(0, 1000000, 500), 0.0);
  const double stale_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - last_publish)
          .count();
  std::printf("disarmed %.1f ms after the last motor_pwm_t\n", stale_ms);
  EXPECT_GE(stale_ms, 50.0);  // never before the timeout
  EXPECT_LE(stale_ms, kStaleBoundMs);
  // Armed, then SIGTERM: disarmed, exit 0.
  publish(lcm, {1800, 1800, 1800, 1800}, true);
  ASSERT_GE(wait_duty(2, 1800000, kApplyBoundMs), 0.0);
  output.signal(SIGTERM);
  EXPECT_EQ(output.wait_for(3s), 0);
  EXPECT_EQ(duty(2), 1000000);
  std::ifstream log(root_ + "/output.log");
  const std::string text((std::istreambuf_iterator<char>(log)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("1 not finite"), std::string::npos) << text;
  EXPECT_NE(text.find("values clamped"), std::string::npos) << text;
}

TEST_F(OutputProcess, OutputStatusSaysWhatThePinsCarryAndWhatWasRefused) {
  ChildProcess output({motormix_binary(), "output", "--config", config_}, root_ + "/output.log");
  lcm::LCM lcm;
  ASSERT_TRUE(lcm.good());
  std::mutex mutex;
  std::vector<motormix::output_status_t> got;
  struct Handler {
    std::mutex* mutex;
    std::vector<motormix::output_status_t>* got;
    void on(const lcm::ReceiveBuffer*, const std::string&, const motormix::output_status_t* m) {
      std::lock_guard<std::mutex> lock(*mutex);
      got->push_back(*m);
    }
  } handler{&mutex, &got};
  lcm.subscribe("OUTPUT_STATUS", &Handler::on, &handler);
  std::atomic<bool> stop{false};
  std::thread receiver([&] {
    while (!stop) lcm.handleTimeout(20);
  });
  const JoinOnExit join{&stop, &receiver};  // on every way out, failed assertions included
  // The newest status once it satisfies `ok`, within 2 s (it comes at 10
  // Hz); `each` runs every 2.5 ms meanwhile (a publisher keeping it armed).
  const auto wait_status = [&](auto ok, auto each) -> std::optional<motormix::output_status_t> {
    for (int i = 0; i < 800; ++i) {
      {
        std::lock_guard<std::mutex> lock(mutex);
        if (!got.empty() && ok(got.back())) return got.back();
      }
      each();
      std::this_thread::sleep_for(2500us);
    }
    return std::nullopt;
  };
  const auto nothing = [] {};
  using S = motormix::output_status_t;
  auto st = wait_status([](const S& m) { return m.pins == S::PINS_STARTING; }, nothing);
  ASSERT_TRUE(st) << "no output_status_t while starting";
  EXPECT_EQ(st->driver, S::DRIVER_SYSFS);
  EXPECT_EQ(st->num_motors, 4);
  EXPECT_FALSE(st->firmware_report);
  EXPECT_TRUE(st->device_open);
  EXPECT_EQ(st->device_reopened, 0);
  EXPECT_EQ(st->pulse[0], 1000.0f);

  // Armed, a NaN, two bytes that are no message, armed again.
  for (int i = 0; i < 10; ++i) {
    publish(lcm, {1500, 1600, 1700, 1800}, true);
    std::this_thread::sleep_for(2500us);
  }
  publish(lcm, {std::numeric_limits<float>::quiet_NaN(), 1900, 1900, 1900}, true);
  const std::uint8_t junk[2] = {1, 2};
  lcm.publish("MOTOR_PWM", junk, sizeof junk);
  st = wait_status(
      [](const S& m) {
        return m.pins == S::PINS_ARMED && m.refused_not_finite == 1 && m.refused_malformed == 1;
      },
      [&] {
        publish(lcm, {1500, 1600, 1700, 1800}, true);
      });
  ASSERT_TRUE(st) << "armed, with the NaN and the junk counted";
  EXPECT_GE(st->taken, 11);
  EXPECT_EQ(st->refused_signature, 0);
  // Quiet: stale after the timeout, counted once.
  st = wait_status([](const S& m) { return m.pins == S::PINS_STALE; }, nothing);
  ASSERT_TRUE(st) << "never stale";
  EXPECT_EQ(st->stale_events, 1);
  EXPECT_EQ(st->pulse[3], 1000.0f);
  output.signal(SIGTERM);
  EXPECT_EQ(output.wait_for(3s), 0);
}

// The newest output_status_t a test's LCM handler was given.
struct LastOutputStatus {
  std::optional<motormix::output_status_t> status;
  void on(const lcm::ReceiveBuffer*, const std::string&, const motormix::output_status_t* m) {
    status = *m;
  }
};

// A pseudo-terminal whose slave side the output opens by a path that the
// test points at it (a symlink, as udev names a USB adapter).
struct Pty {
  int master = -1;
  std::string slave;
  std::uint32_t session = 0x10001;
  mm_link_frame last{};  // the last frame frames_until read
  Pty() {
    // Close-on-exec: a copy in the output process would keep the line up.
    master = posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (master < 0) return;
    grantpt(master);
    unlockpt(master);
    char name[128];
    ptsname_r(master, name, sizeof name);
    slave = name;
  }
  ~Pty() { close(); }
  void close() {
    if (master >= 0) ::close(master);
    master = -1;
  }
  // The frame types read within `bound_ms`, up to and including `until`,
  // with a report naming this chip's session every 50 ms, as the firmware
  // sends (the host sends nothing before it has one).
  std::vector<int> frames_until(int until, double bound_ms) {
    std::vector<int> types;
    mm_link_parser parser;
    mm_link_parser_init(&parser);
    const auto start = std::chrono::steady_clock::now();
    auto next_report = start;
    while (std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
               .count() < bound_ms) {
      if (std::chrono::steady_clock::now() >= next_report) {
        mm_link_report r{};
        r.session = session;
        r.version = MM_LINK_VERSION;
        std::uint8_t out[MM_LINK_MAX_FRAME];
        [[maybe_unused]] const ssize_t w = ::write(master, out, mm_link_encode_report(&r, 0, out));
        next_report += 50ms;
      }
      std::uint8_t buf[256];
      const ssize_t n = ::read(master, buf, sizeof buf);
      for (ssize_t i = 0; i < n; ++i) {
        mm_link_frame f{};
        const std::uint8_t type = mm_link_feed(&parser, buf[i], &f);
        if (type == 0) continue;
        types.push_back(type);
        last = f;
        if (type == until) return types;
      }
      if (n <= 0) std::this_thread::sleep_for(1ms);
    }
    return types;
  }
};

// KISS telemetry asked for and matched. The output drives DShot600 through
// a chip emulated on a pseudo-terminal, with two ESC telemetry wires
// (motors 2 and 4) on two more; each emulated ESC answers only a PULSES
// frame that asks it (the telemetry bit of its channel), a third of its
// frames corrupted. The output asks the two in turn, every good answer comes
// out as esc_telemetry_t for its motor, stamped no later than it arrived,
// and no bad one; the log counts what was asked and answered.
TEST_F(OutputProcess, KissTelemetryIsAskedInTurnAndEachAnswerComesOutForItsMotor) {
  Pty chip, second_wire;
  ASSERT_GE(chip.master, 0);
  ASSERT_GE(second_wire.master, 0);
  const std::string config = root_ + "/kiss.yaml";
  std::ofstream(config) << "geometry: {preset: quad_x}\n"
                           "output: {min: 1000, max: 2000, disarmed: 1000}\n"
                           "hardware:\n"
                           "  driver: serial\n"
                           "  protocol: dshot600\n"
                           "  pulse_rate_hz: 400\n"
                           "  serial: {device: "
                        << chip.slave << "}\n  telemetry: [{device: " << wire_
                        << ", motor: 2}, {device: " << second_wire.slave << ", motor: 4}]\n";
  ChildProcess output({motormix_binary(), "output", "--config", config}, root_ + "/kiss.log");
  lcm::LCM lcm;
  ASSERT_TRUE(lcm.good());
  std::mutex mutex;
  std::vector<std::pair<motormix::esc_telemetry_t, std::int64_t>> got;  // and when it came
  struct Handler {
    std::mutex* mutex;
    std::vector<std::pair<motormix::esc_telemetry_t, std::int64_t>>* got;
    void on(const lcm::ReceiveBuffer*, const std::string&, const motormix::esc_telemetry_t* m) {
      const auto now = std::chrono::duration_cast<std::chrono::microseconds>(
                           std::chrono::system_clock::now().time_since_epoch())
                           .count();
      std::lock_guard<std::mutex> lock(*mutex);
      got->emplace_back(*m, now);
    }
  } handler{&mutex, &got};
  lcm.subscribe("ESC_TELEMETRY", &Handler::on, &handler);
  std::atomic<bool> stop{false};
  std::thread receiver([&] {
    while (!stop) lcm.handleTimeout(20);
  });
  const JoinOnExit join{&stop, &receiver};
  // The chip: a report every 50 ms naming its session; each PULSES frame
  // read; the asked ESC answers on its wire.
  constexpr int kAnswers = 120;
  std::mt19937 rng(1234);
  mm_link_parser parser;
  mm_link_parser_init(&parser);
  std::vector<int> asked;  // motor (1-based) of each request, in order
  int good = 0, sent = 0, pulses = 0;
  const auto start = std::chrono::steady_clock::now();
  auto next_report = start;
  while (sent < kAnswers && std::chrono::steady_clock::now() - start < 10s) {
    if (std::chrono::steady_clock::now() >= next_report) {
      mm_link_report r{};
      r.session = chip.session;
      r.version = MM_LINK_VERSION;
      r.flags = MM_LINK_FLAG_CONFIGURED;
      std::uint8_t out[MM_LINK_MAX_FRAME];
      [[maybe_unused]] const ssize_t w =
          ::write(chip.master, out, mm_link_encode_report(&r, 0, out));
      next_report += 50ms;
    }
    std::uint8_t buf[256];
    const ssize_t n = ::read(chip.master, buf, sizeof buf);
    // Several frames can come in one read: no answer beyond kAnswers.
    for (ssize_t i = 0; i < n && sent < kAnswers; ++i) {
      mm_link_frame f{};
      if (mm_link_feed(&parser, buf[i], &f) != MM_LINK_PULSES) continue;
      ++pulses;
      if (f.u.pulses.telemetry == 0) continue;
      const int motor = f.u.pulses.telemetry;  // channel + 1
      asked.push_back(motor);
      if (motor != 2 && motor != 4) continue;  // no wire: nobody answers
      output::KissReading r;
      r.temperature_c = 30 + sent % 20;
      r.voltage_v = 15.0 + (sent % 100) / 100.0;
      r.current_a = 5.0 + (sent % 50) / 10.0;
      r.consumption_mah = 100 + sent;
      r.erpm = 20000 + 100 * sent;
      auto frame = kiss_esc_frame(r);
      if (sent % 3 == 2) {
        frame[rng() % frame.size()] ^= static_cast<std::uint8_t>(1u << (rng() % 8));
      } else {
        ++good;
      }
      const int wire = motor == 2 ? master_ : second_wire.master;
      ASSERT_EQ(::write(wire, frame.data(), frame.size()), static_cast<ssize_t>(frame.size()));
      ++sent;
    }
    if (n <= 0) std::this_thread::sleep_for(500us);
  }
  ASSERT_EQ(sent, kAnswers) << "requests seen: " << asked.size() << " in " << pulses << " frames";
  std::this_thread::sleep_for(300ms);
  output.signal(SIGTERM);
  EXPECT_EQ(output.wait_for(3s), 0);
  // Asked in turn: motors 2 and 4 alternate, no other asked.
  for (std::size_t i = 0; i < asked.size(); ++i) {
    ASSERT_TRUE(asked[i] == 2 || asked[i] == 4) << "request " << i << " for motor " << asked[i];
    if (i > 0) {
      EXPECT_NE(asked[i], asked[i - 1]) << "request " << i << " not in turn";
    }
  }
  stop = true;
  if (receiver.joinable()) receiver.join();
  std::lock_guard<std::mutex> lock(mutex);
  EXPECT_EQ(static_cast<int>(got.size()), good);
  int on_two = 0, on_four = 0;
  for (const auto& [m, arrived_us] : got) {
    ASSERT_EQ(m.count, 1);
    EXPECT_TRUE(m.motor[0] == 2 || m.motor[0] == 4);
    (m.motor[0] == 2 ? on_two : on_four) += 1;
    EXPECT_TRUE(std::isnan(m.rpm[0]));
    EXPECT_GE(m.erpm[0], 20000.0f);
    EXPECT_GE(m.voltage_v[0], 15.0f);
    EXPECT_LE(m.voltage_v[0], 16.0f);
    EXPECT_LE(m.utime, arrived_us) << "stamped when asked, never later than it came";
  }
  EXPECT_GT(on_two, 0);
  EXPECT_GT(on_four, 0);
  std::ifstream in(root_ + "/kiss.log");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("KISS telemetry: "), std::string::npos) << text;
  EXPECT_NE(text.find(" unasked"), std::string::npos) << text;
}

TEST_F(OutputProcess, ALostSerialDeviceIsReopenedAndTheFirmwareConfiguredAgain) {
  auto first = std::make_unique<Pty>();
  ASSERT_GE(first->master, 0);
  const std::string link = root_ + "/ttyMOTORS";
  ASSERT_EQ(::symlink(first->slave.c_str(), link.c_str()), 0);
  const std::string config = root_ + "/serial.yaml";
  std::ofstream(config) << "geometry: {preset: quad_x}\n"
                           "output: {min: 1000, max: 2000, disarmed: 1000}\n"
                           "hardware:\n"
                           "  driver: serial\n"
                           "  serial: {device: "
                        << link << ", link_timeout_ms: 100}\n";
  ChildProcess output({motormix_binary(), "output", "--config", config}, root_ + "/serial.log");
  // Configured, then pulses.
  std::vector<int> types = first->frames_until(MM_LINK_CONFIG, 3000);
  ASSERT_FALSE(types.empty()) << "no CONFIG frame at start";
  EXPECT_EQ(types.back(), MM_LINK_CONFIG);
  types = first->frames_until(MM_LINK_PULSES, 1000);
  ASSERT_FALSE(types.empty());
  EXPECT_EQ(types.back(), MM_LINK_PULSES);

  // The adapter goes away; a new one appears under the same name.
  first->close();
  std::this_thread::sleep_for(200ms);
  Pty second;
  ASSERT_GE(second.master, 0);
  const std::string tmp_link = link + ".new";
  ASSERT_EQ(::symlink(second.slave.c_str(), tmp_link.c_str()), 0);
  ASSERT_EQ(::rename(tmp_link.c_str(), link.c_str()), 0);
  // Reopened (tried every 0.5 s): CONFIG before any PULSES.
  types = second.frames_until(MM_LINK_CONFIG, 3000);
  const auto log_text = [&] {
    std::ifstream in(root_ + "/serial.log");
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  ASSERT_FALSE(types.empty()) << "never reopened: " << log_text();
  EXPECT_EQ(types.front(), MM_LINK_CONFIG) << "pulses before the configuration";
  types = second.frames_until(MM_LINK_PULSES, 1000);
  ASSERT_FALSE(types.empty());
  EXPECT_EQ(types.back(), MM_LINK_PULSES);
  EXPECT_TRUE(output.running());
  // Its status says so.
  lcm::LCM lcm;
  ASSERT_TRUE(lcm.good());
  LastOutputStatus last;
  lcm.subscribe("OUTPUT_STATUS", &LastOutputStatus::on, &last);
  for (int i = 0; i < 100 && !(last.status && last.status->device_reopened == 1); ++i)
    lcm.handleTimeout(20);
  ASSERT_TRUE(last.status.has_value()) << "no output_status_t";
  EXPECT_TRUE(last.status->device_open);
  EXPECT_EQ(last.status->device_reopened, 1);
  EXPECT_EQ(last.status->driver, motormix::output_status_t::DRIVER_SERIAL);
  output.signal(SIGTERM);
  EXPECT_EQ(output.wait_for(3s), 0);
  const std::string text = log_text();
  EXPECT_NE(text.find("motormix output: lost " + link), std::string::npos) << text;
  EXPECT_NE(text.find("motormix output: reopened " + link), std::string::npos) << text;
}

// A DShot special command from `motormix esc-command` reaches the firmware
// through the output as a COMMAND frame while every output is disarmed,
// and is refused (exit 5, no frame) while the mixer's outputs are armed.
TEST_F(OutputProcess, EscCommandsReachTheFirmwareOnlyWhileDisarmed) {
  Pty pty;
  ASSERT_GE(pty.master, 0);
  const std::string config = root_ + "/dshot.yaml";
  std::ofstream(config) << "geometry: {preset: quad_x}\n"
                           "output: {min: 1000, max: 2000, disarmed: 1000}\n"
                           "hardware:\n"
                           "  driver: serial\n"
                           "  protocol: dshot600\n"
                           "  serial: {device: "
                        << pty.slave << "}\n";
  ChildProcess output({motormix_binary(), "output", "--config", config}, root_ + "/dshot.log");
  std::vector<int> types = pty.frames_until(MM_LINK_CONFIG, 3000);
  ASSERT_FALSE(types.empty()) << "no CONFIG frame";
  EXPECT_EQ(pty.last.u.config.protocol, MM_LINK_PROTOCOL_DSHOT600);
  {
    ChildProcess cli({motormix_binary(), "esc-command", "--config", config, "spin-reversed",
                      "--motor", "2", "--motor", "4"},
                     root_ + "/esc-command.log");
    types = pty.frames_until(MM_LINK_COMMAND, 4000);
    ASSERT_FALSE(types.empty());
    ASSERT_EQ(types.back(), MM_LINK_COMMAND);
    EXPECT_EQ(pty.last.u.command.command, 21);
    EXPECT_EQ(pty.last.u.command.channels, 0b1010);
    EXPECT_EQ(pty.last.u.command.repeat, 10);
    EXPECT_EQ(pty.last.u.command.session, pty.session);
    pty.frames_until(-1, 500);  // reports keep coming while the client reads the status
    EXPECT_EQ(cli.wait_for(3s), 0);
  }
  // Armed: refused, nothing on the line but pulses.
  lcm::LCM lcm;
  ASSERT_TRUE(lcm.good());
  std::atomic<bool> stop{false};
  std::thread mixer([&] {
    motormix::motor_pwm_t m{};
    m.num_motors = 4;
    m.pwm.assign(4, 1200.0f);
    m.command.assign(4, 0.2f);
    m.direction.assign(4, 0);
    m.armed = true;
    for (int k = 0; k < 1000 && !stop; ++k) {
      m.utime = k;
      lcm.publish("MOTOR_PWM", &m);
      std::this_thread::sleep_for(5ms);
    }
  });
  pty.frames_until(-1, 300);
  ChildProcess refused({motormix_binary(), "esc-command", "--config", config, "save", "--all"},
                       root_ + "/esc-command-refused.log");
  types = pty.frames_until(MM_LINK_COMMAND, 2500);
  stop = true;
  mixer.join();
  EXPECT_TRUE(std::find(types.begin(), types.end(), MM_LINK_COMMAND) == types.end());
  EXPECT_EQ(refused.wait_for(3s), 5);
  // A flood of commands out of range (and bytes that are none): each one
  // refused and counted, the log a few lines.
  constexpr int kFlood = 300;
  LastOutputStatus last;
  lcm.subscribe("OUTPUT_STATUS", &LastOutputStatus::on, &last);
  for (int k = 0; k < kFlood; ++k) {
    motormix::esc_command_t c{};
    c.command = static_cast<std::int8_t>(k % 2 == 0 ? 0 : 48);
    c.motors = 1;
    c.repeat = 1;
    lcm.publish("ESC_COMMAND", &c);
    const std::uint8_t junk[5] = {1, 2, 3, 4, 5};
    lcm.publish("ESC_COMMAND", junk, sizeof junk);
  }
  // Until the count holds still (a burst this size loses some datagrams
  // to the socket buffers before the output reads them: never counted).
  std::int64_t seen = -1;
  for (int i = 0; i < 20; ++i) {
    pty.frames_until(-1, 200);
    while (lcm.handleTimeout(0) > 0) {
    }
    if (last.status && last.status->esc_commands_refused == seen) break;
    if (last.status) seen = last.status->esc_commands_refused;
  }
  ASSERT_TRUE(last.status.has_value());
  EXPECT_GE(last.status->esc_commands_refused, 1 + kFlood / 2);
  EXPECT_LE(last.status->esc_commands_refused, 2 * kFlood + 1);
  EXPECT_EQ(last.status->esc_commands_sent, 1);
  EXPECT_EQ(last.status->refused_malformed, 0);  // motor_pwm_t's count
  output.signal(SIGTERM);
  EXPECT_EQ(output.wait_for(3s), 0);
  std::ifstream in(root_ + "/dshot.log");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("ESC command 21 sent"), std::string::npos) << text;
  EXPECT_NE(text.find("ESC command 12 refused: an output is armed"), std::string::npos) << text;
  int lines = 0;
  for (std::size_t at = text.find("ESC command"); at != std::string::npos;
       at = text.find("ESC command", at + 1))
    ++lines;
  EXPECT_LE(lines, 10) << text;
}

TEST_F(OutputProcess, UnderRequireOnlySignedMotorPwmMovesThePins) {
  const std::string key_path = root_ + "/bus.key";
  signing::write_new_key(key_path);
  std::ofstream(config_, std::ios::app) << "security: {mode: require, key_file: bus.key}\n";
  ChildProcess output({motormix_binary(), "output", "--config", config_}, root_ + "/output.log");
  lcm::LCM lcm;
  ASSERT_TRUE(lcm.good());
  ASSERT_GE(wait_duty(0, 1000000, 3000), 0.0) << "no disarmed duty at start";
  signing::Policy mixer(signing::Mode::kRequire, signing::load_key(key_path), 1);
  signing::Policy stranger(signing::Mode::kRequire, signing::Key{}, 1);
  signing::Policy none;
  // Signed earlier, sent later: a replay.
  const std::vector<std::uint8_t> captured = encoded({1900, 1900, 1900, 1900}, true, mixer);
  // Subscribed once a signed message moves a pin; then stale: disarmed.
  for (int i = 0; i < 100 && duty(0) != 1400000; ++i) {
    send(lcm, encoded({1400, 1400, 1400, 1400}, true, mixer));
    std::this_thread::sleep_for(20ms);
  }
  ASSERT_EQ(duty(0), 1400000);
  ASSERT_GE(wait_duty(0, 1000000, 500), 0.0);
  // Each refused message is looked for at once, in every channel: a taken
  // one is written in its callback, and read here within the 50 ms before
  // the staleness timeout would disarm the pins again (a check after the
  // timeout passes whether or not the verdict was obeyed).
  int moved = 0;
  const auto pins_moved = [&] {
    int n = 0;
    for (int c = 0; c < 4; ++c) n += duty(c) != 1000000 ? 1 : 0;
    return n;
  };
  for (int i = 0; i < 20; ++i) {
    send(lcm, encoded({1600, 1600, 1600, 1600}, true, none));
    std::this_thread::sleep_for(2500us);
    moved += pins_moved();
    send(lcm, encoded({1700, 1700, 1700, 1700}, true, stranger));
    std::this_thread::sleep_for(2500us);
    moved += pins_moved();
  }
  EXPECT_EQ(moved, 0) << "an unsigned or forged motor_pwm_t moved a pin";
  // Signed with the key: taken.
  send(lcm, encoded({1500, 1500, 1500, 1500}, true, mixer));
  EXPECT_GE(wait_duty(0, 1500000, kApplyBoundMs), 0.0);
  // The replay, looked for at once: had it been taken, 1900 is written.
  send(lcm, captured);
  std::this_thread::sleep_for(2500us);
  EXPECT_NE(duty(0), 1900000) << "a replayed motor_pwm_t moved a pin";
  send(lcm, encoded({1501, 1501, 1501, 1501}, true, mixer));
  EXPECT_GE(wait_duty(0, 1501000, kApplyBoundMs), 0.0);
  // Never 1900 on any channel at any point: the log's replay count below.
  output.signal(SIGTERM);
  EXPECT_EQ(output.wait_for(3s), 0);
  std::ifstream log(root_ + "/output.log");
  const std::string text((std::istreambuf_iterator<char>(log)), std::istreambuf_iterator<char>());
  // Every signed one verified but the replay (how many it took to see the
  // process subscribed varies; it is 3 more than that).
  const auto at = text.rfind(
      " verified, 0 unsigned taken, refused 20 unsigned, 20 bad, 1 replayed, "
      "0 stale");
  ASSERT_NE(at, std::string::npos) << text;
  const auto from = text.rfind("signatures: ", at);
  ASSERT_NE(from, std::string::npos) << text;
  EXPECT_GE(std::stoi(text.substr(from + 12, at - from - 12)), 3) << text;
  EXPECT_NE(text.find("security: require"), std::string::npos) << text;
}

}  // namespace
}  // namespace motormix::test
