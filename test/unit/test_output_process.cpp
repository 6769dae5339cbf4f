// `motormix output`'s parts without a bus: the output gate (the failsafe
// every driver sits behind), the `hardware:` section's checks, the sysfs
// PWM driver against a tree in a temporary directory (the order of its
// writes as the kernel documents it), and the serial driver against the
// firmware's end of a pseudo-terminal (frames out, reports in, a chip that
// lost its configuration configured again).

#include "output/erpm_telemetry.hpp"
#include "output/output_gate.hpp"
#include "output/serial_port.hpp"
#include "output/serial_pulse_driver.hpp"
#include "output/sysfs_pwm_driver.hpp"
#include "output/telemetry_requests.hpp"

#include "bus/clock.hpp"

#include <motormix/config/load_config.hpp>

#include <gtest/gtest.h>

#include <fcntl.h>
#include <unistd.h>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace motormix::test {
namespace {

constexpr double kGateTimeoutS = 0.05;

output::OutputGate quad_gate() {
  return output::OutputGate(
      {{1000, 2000, 1000}, {1000, 2000, 1000}, {1100, 1900, 1050}, {1000, 2000, 900}},
      kGateTimeoutS);
}

TEST(OutputGate, DisarmedAtStartOnArmedFalseAndWhenStale) {
  output::OutputGate gate = quad_gate();
  double out[4];
  EXPECT_EQ(gate.decide(0.0, out), output::GateState::kStarting);
  EXPECT_EQ(out[2], 1050);
  EXPECT_EQ(out[3], 900);
  const float armed[4] = {1500, 1600, 1700, 1800};
  ASSERT_TRUE(gate.accept(armed, 4, true, 0, 1.0));
  EXPECT_EQ(gate.decide(1.0, out), output::GateState::kArmed);
  EXPECT_EQ(out[1], 1600);
  EXPECT_EQ(gate.decide(1.0 + kGateTimeoutS * 0.99, out), output::GateState::kArmed);
  EXPECT_EQ(gate.decide(1.0 + kGateTimeoutS * 1.01, out), output::GateState::kStale);
  EXPECT_EQ(out[0], 1000);
  EXPECT_EQ(gate.decide(2.0, out), output::GateState::kStale);
  EXPECT_EQ(gate.counters().stale_events, 1u);  // counted once per loss
  ASSERT_TRUE(gate.accept(armed, 4, false, 0, 3.0));
  EXPECT_EQ(gate.decide(3.0, out), output::GateState::kDisarmed);
  EXPECT_EQ(out[1], 1000);
}

// The mixer's motor test through the output: one motor's value reaches its
// pin within this process's own limits, the others stay disarmed; refused
// without its guards.
TEST(OutputGate, AMotorTestReachesOnePinWithinTheOutputsOwnLimits) {
  output::BringupLimits limits;
  limits.max_share = 0.15;
  limits.max_seconds = 2.0;
  output::OutputGate gate(
      {{1000, 2000, 1000}, {1000, 2000, 1000}, {1100, 1900, 1050}, {1000, 2000, 900}},
      kGateTimeoutS, limits);
  double out[4];
  // Motor 2 at 10 %: 1100 us; the others' values are ignored (disarmed).
  const float test[4] = {1000, 1100, 1500, 1900};
  ASSERT_TRUE(gate.accept(test, 4, false, 1U << 1, 0.0));
  EXPECT_EQ(gate.decide(0.0, out), output::GateState::kMotorTest);
  EXPECT_EQ(gate.bringup(), 1U << 1);
  EXPECT_EQ(out[0], 1000);
  EXPECT_EQ(out[1], 1100);
  EXPECT_EQ(out[2], 1050);
  EXPECT_EQ(out[3], 900);
  // Above max_throttle of the range: clamped to it (1150 us), counted.
  const float high[4] = {1000, 1900, 1050, 900};
  ASSERT_TRUE(gate.accept(high, 4, false, 1U << 1, 0.01));
  gate.decide(0.01, out);
  EXPECT_EQ(out[1], 1150);
  EXPECT_EQ(gate.counters().bringup_clamped, 1u);
  // Two motors at once, or a motor the vehicle does not have: refused.
  EXPECT_FALSE(gate.accept(test, 4, false, 0b11U, 0.02));
  EXPECT_FALSE(gate.accept(test, 4, false, 1U << 4, 0.02));
  EXPECT_EQ(gate.counters().bringup_refused, 2u);
  // Stale: disarmed, as any message.
  EXPECT_EQ(gate.decide(0.01 + kGateTimeoutS * 1.01, out), output::GateState::kStale);
  EXPECT_EQ(out[1], 1000);
  // Longer than max_seconds (and its grace) while the messages keep coming:
  // disarmed until a message without the test.
  double t = 1.0;
  for (; t < 1.0 + limits.max_seconds + output::BringupLimits::kGraceS + 0.1; t += 0.01) {
    ASSERT_TRUE(gate.accept(test, 4, false, 1U << 1, t));
    gate.decide(t, out);
  }
  EXPECT_EQ(gate.decide(t, out), output::GateState::kDisarmed);
  EXPECT_EQ(out[1], 1000);
  const float disarmed[4] = {1000, 1000, 1050, 900};
  ASSERT_TRUE(gate.accept(disarmed, 4, false, 0, t + 0.01));
  ASSERT_TRUE(gate.accept(test, 4, false, 1U << 1, t + 0.02));
  EXPECT_EQ(gate.decide(t + 0.02, out), output::GateState::kMotorTest);
  // Armed messages are armed values: the mask means nothing then.
  const float armed[4] = {1500, 1600, 1700, 1800};
  ASSERT_TRUE(gate.accept(armed, 4, true, 1U << 1, t + 0.03));
  EXPECT_EQ(gate.decide(t + 0.03, out), output::GateState::kArmed);
  EXPECT_EQ(out[1], 1600);
  // A reversible drive stopped at the middle of its range: max_share of a
  // half range either way (1425..1575 us), never an end.
  output::OutputGate centered({{1000, 2000, 1500}}, kGateTimeoutS, limits);
  const float forward[1] = {1550}, far_forward[1] = {1900}, far_back[1] = {1000};
  ASSERT_TRUE(centered.accept(forward, 1, false, 1U, 0.0));
  centered.decide(0.0, out);
  EXPECT_EQ(out[0], 1550);
  ASSERT_TRUE(centered.accept(far_forward, 1, false, 1U, 0.01));
  centered.decide(0.01, out);
  EXPECT_EQ(out[0], 1575);
  ASSERT_TRUE(centered.accept(far_back, 1, false, 1U, 0.02));
  centered.decide(0.02, out);
  EXPECT_EQ(out[0], 1425);
  // Motor tests disabled in the output's configuration: refused.
  output::BringupLimits off;
  off.enabled = false;
  output::OutputGate closed({{1000, 2000, 1000}}, kGateTimeoutS, off);
  const float one[1] = {1100};
  EXPECT_FALSE(closed.accept(one, 1, false, 1U, 0.0));
  EXPECT_EQ(closed.decide(0.0, out), output::GateState::kStarting);
}

TEST(OutputGate, ClampsArmedValuesAndRefusesWrongSizesAndNonFiniteValues) {
  output::OutputGate gate = quad_gate();
  double out[4];
  const float wide[4] = {900, 2500, 1000, 1500};
  ASSERT_TRUE(gate.accept(wide, 4, true, 0, 0.0));
  gate.decide(0.0, out);
  EXPECT_EQ(out[0], 1000);
  EXPECT_EQ(out[1], 2000);
  EXPECT_EQ(out[2], 1100);  // this motor's own range
  EXPECT_EQ(gate.counters().clamped, 3u);
  const float nan[4] = {1500, std::numeric_limits<float>::quiet_NaN(), 1500, 1500};
  const float inf[4] = {1500, 1500, std::numeric_limits<float>::infinity(), 1500};
  EXPECT_FALSE(gate.accept(nan, 4, true, 0, 0.01));
  EXPECT_FALSE(gate.accept(inf, 4, true, 0, 0.01));
  EXPECT_FALSE(gate.accept(wide, 3, true, 0, 0.01));
  // Further out than the range is wide: refused, not clamped to full thrust.
  const float huge[4] = {1500, 1e30f, 1500, 1500};
  const float below[4] = {1500, 1500, 1500, -1e30f};
  EXPECT_FALSE(gate.accept(huge, 4, true, 0, 0.01));
  EXPECT_FALSE(gate.accept(below, 4, true, 0, 0.01));
  EXPECT_EQ(gate.counters().out_of_range, 2u);
  EXPECT_EQ(gate.counters().not_finite, 2u);
  EXPECT_EQ(gate.counters().wrong_size, 1u);
  // The refused ones changed nothing, and did not keep the stream alive.
  EXPECT_EQ(gate.decide(0.02, out), output::GateState::kArmed);
  EXPECT_EQ(out[1], 2000);
  EXPECT_EQ(gate.decide(0.06, out), output::GateState::kStale);
}

std::string expect_hardware_error(const std::string& hardware, const std::string& output = "") {
  try {
    config::load_config_text("geometry: {preset: quad_x}\n" + output + "hardware:\n" + hardware,
                             "test");
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  ADD_FAILURE() << "accepted: " << hardware;
  return "";
}

// KISS requests in turn over the wired motors; a reading answers the open
// request of its motor within the window (stamped when it was asked), and is
// unasked otherwise; a request nobody answers in the window, or before the
// next one to the same ESC, is counted unanswered.
TEST(TelemetryRequests, AskInTurnAndMatchEachReadingToItsRequest) {
  constexpr double kWindowS = 0.03;
  output::TelemetryRequests r({1, 3}, kWindowS);
  EXPECT_EQ(r.next(), 1);
  r.asked(1, 10.000);
  EXPECT_EQ(r.next(), 3);
  r.asked(3, 10.0025);
  EXPECT_EQ(r.next(), 1);
  const std::optional<double> first = r.answered(1, 10.004);
  ASSERT_TRUE(first.has_value());
  EXPECT_DOUBLE_EQ(*first, 10.000);
  EXPECT_FALSE(r.answered(1, 10.005).has_value()) << "one answer per request";
  EXPECT_FALSE(r.answered(2, 10.005).has_value()) << "no wire, never asked";
  // Motor 3's request expires unanswered; its late reading is unasked.
  EXPECT_FALSE(r.answered(3, 10.0025 + kWindowS + 0.001).has_value());
  r.asked(1, 10.1);
  r.asked(3, 10.1025);
  r.asked(1, 10.105);  // motor 1's request of 10.1 never answered
  const output::TelemetryRequests::Counts& c = r.counts();
  EXPECT_EQ(c.asked, 5u);
  EXPECT_EQ(c.answered, 1u);
  EXPECT_EQ(c.unasked, 3u);
  EXPECT_EQ(c.unanswered, 2u);
  EXPECT_EQ(output::TelemetryRequests({}, kWindowS).next(), -1);
}

TEST(OutputHardwareConfig, RefusesWhatNoDriverCanMakeNamingKeyValueAndRange) {
  EXPECT_NE(expect_hardware_error("  driver: serial\n").find("hardware.serial.device"),
            std::string::npos);
  EXPECT_NE(expect_hardware_error("  driver: pigeon\n").find("hardware.driver"), std::string::npos);
  EXPECT_NE(expect_hardware_error("  driver: sysfs\n  pulse_rate_hz: 900\n").find("pulse_rate_hz"),
            std::string::npos);
  // 490 Hz leaves 2040 us: a 2000 us pulse needs 40 us low before the next.
  const std::string too_long = expect_hardware_error("  driver: sysfs\n  pulse_rate_hz: 495\n");
  EXPECT_NE(too_long.find("2000"), std::string::npos) << too_long;
  EXPECT_NE(expect_hardware_error("  driver: sysfs\n  sysfs: {channels: [0, 1, 1, 2]}\n")
                .find("hardware.sysfs.channels[2]"),
            std::string::npos);
  EXPECT_NE(expect_hardware_error("  driver: sysfs\n  sysfs: {channels: [0, 1]}\n").find("4"),
            std::string::npos);
  EXPECT_NE(expect_hardware_error("  driver: sysfs\n  telemetry: [{device: /dev/null, motor: 5}]\n")
                .find("hardware.telemetry[0].motor"),
            std::string::npos);
  // KISS wires hear only what a DShot frame's telemetry bit asks for:
  // refused with servo PWM, on either driver, naming why.
  for (const char* driver : {"sysfs", "serial\n  serial: {device: /dev/ttyUSB0}"}) {
    const std::string pwm_wire = expect_hardware_error(
        std::string("  driver: ") + driver + "\n  telemetry: [{device: /dev/null, motor: 2}]\n");
    EXPECT_NE(pwm_wire.find("'hardware.telemetry'"), std::string::npos) << pwm_wire;
    EXPECT_NE(pwm_wire.find("telemetry bit"), std::string::npos) << pwm_wire;
  }
  EXPECT_NE(
      expect_hardware_error("  driver: sysfs\n", "output: {unit: duty}\n").find("output.unit"),
      std::string::npos);
  const config::Config ok = config::load_config_text(
      "geometry: {preset: quad_x}\nhardware: {driver: serial, serial: {device: /dev/ttyUSB0}}\n",
      "test");
  EXPECT_EQ(ok.hardware.driver, config::HardwareDriver::kSerial);
  EXPECT_DOUBLE_EQ(ok.hardware.motor_pwm_timeout_s, 0.05);
  EXPECT_DOUBLE_EQ(ok.hardware.serial.link_timeout_s, 0.1);
}

TEST(OutputHardwareConfig, DshotOnlyThroughTheFirmwareOnPortDAndUnipolar) {
  const std::string serial = "  driver: serial\n  serial: {device: /dev/ttyUSB0}\n";
  const std::string sysfs = expect_hardware_error("  driver: sysfs\n  protocol: dshot600\n");
  EXPECT_NE(sysfs.find("hardware.protocol"), std::string::npos) << sysfs;
  EXPECT_NE(sysfs.find("serial driver"), std::string::npos) << sysfs;
  EXPECT_NE(expect_hardware_error(serial + "  protocol: dshot1200\n").find("hardware.protocol"),
            std::string::npos);
  EXPECT_NE(expect_hardware_error(serial + "  protocol: dshot300\n  pulse_rate_hz: 5000\n")
                .find("hardware.pulse_rate_hz"),
            std::string::npos);
  const std::string centered =
      expect_hardware_error(serial + "  protocol: dshot600\n", "output: {mode: centered}\n");
  EXPECT_NE(centered.find("output.mode"), std::string::npos) << centered;
  std::string octo;
  try {
    config::load_config_text(
        "geometry: {preset: octo_x}\nhardware:\n" + serial + "  protocol: dshot600\n", "test");
  } catch (const config::ConfigError& e) {
    octo = e.what();
  }
  EXPECT_NE(octo.find("D2..D7"), std::string::npos) << octo;
  // 2 kHz frames: too fast for servo pulses, the default for nothing, fine for DShot.
  const config::Config ok =
      config::load_config_text("geometry: {preset: quad_x}\nhardware:\n" + serial +
                                   "  protocol: dshot600\n  pulse_rate_hz: 2000\n",
                               "test");
  EXPECT_EQ(ok.hardware.protocol, config::EscProtocol::kDshot600);
  EXPECT_DOUBLE_EQ(ok.hardware.pulse_rate_hz, 2000.0);
  const config::Config defaults = config::load_config_text(
      "geometry: {preset: quad_x}\nhardware:\n" + serial + "  protocol: dshot300\n", "test");
  EXPECT_DOUBLE_EQ(defaults.hardware.pulse_rate_hz, 1000.0);
  EXPECT_NE(
      expect_hardware_error(serial + "  pulse_rate_hz: 2000\n").find("hardware.pulse_rate_hz"),
      std::string::npos);
  // Bidirectional: DShot300/600, four motors, at most 1000 frames a second.
  EXPECT_NE(expect_hardware_error(serial + "  protocol: dshot150\n  bidirectional: true\n")
                .find("hardware.bidirectional"),
            std::string::npos);
  EXPECT_NE(
      expect_hardware_error(serial + "  bidirectional: true\n").find("hardware.bidirectional"),
      std::string::npos);
  EXPECT_NE(expect_hardware_error(
                serial + "  protocol: dshot600\n  bidirectional: true\n  pulse_rate_hz: 1100\n")
                .find("hardware.pulse_rate_hz"),
            std::string::npos);
  std::string hexa;
  try {
    config::load_config_text("geometry: {preset: hexa_x}\nhardware:\n" + serial +
                                 "  protocol: dshot600\n  bidirectional: true\n",
                             "test");
  } catch (const config::ConfigError& e) {
    hexa = e.what();
  }
  EXPECT_NE(hexa.find("D2..D5"), std::string::npos) << hexa;
  const config::Config bidir =
      config::load_config_text("geometry: {preset: quad_x}\nhardware:\n" + serial +
                                   "  protocol: dshot300\n  bidirectional: true\n",
                               "test");
  EXPECT_TRUE(bidir.hardware.bidirectional);
  EXPECT_DOUBLE_EQ(bidir.hardware.pulse_rate_hz, 1000.0);
}

// A sysfs PWM tree as the kernel shows it: pwmchip0 with export, and the
// channel directories with their attributes (here: made by the "kernel"
// when export is written, as udev would).
struct FakePwmTree {
  FakePwmTree() {
    char tmpl[] = "/tmp/motormix-pwm-XXXXXX";
    root = mkdtemp(tmpl);
    std::filesystem::create_directories(root + "/pwmchip0");
    std::ofstream(root + "/pwmchip0/export");
  }
  ~FakePwmTree() { std::filesystem::remove_all(root); }
  void make_channel(int c) const {
    const std::string dir = root + "/pwmchip0/pwm" + std::to_string(c);
    std::filesystem::create_directories(dir);
    for (const char* f : {"period", "duty_cycle", "enable"}) std::ofstream(dir + "/" + f);
  }
  std::string read(int c, const char* attr) const {
    std::ifstream in(root + "/pwmchip0/pwm" + std::to_string(c) + "/" + attr);
    std::string v;
    in >> v;
    return v;
  }
  std::string root;
};

TEST(SysfsPwm, ExportsThenSetsPeriodDutyAndEnableInTheKernelsOrder) {
  FakePwmTree tree;
  tree.make_channel(2);  // already exported; 5 is not
  config::SysfsPwm s;
  s.root = tree.root;
  s.channels = {2, 5};
  std::vector<std::pair<std::string, std::string>> writes;
  auto observe = [&](const std::string& path, const std::string& value) {
    writes.emplace_back(path.substr(tree.root.size()), value);
    if (path.size() >= 6 && path.compare(path.size() - 6, 6, "export") == 0)
      tree.make_channel(std::stoi(value));
  };
  output::SysfsPwmDriver driver(s, 2500.0, {1000.0, 1100.0}, observe);
  const std::vector<std::pair<std::string, std::string>> expected = {
      {"/pwmchip0/pwm2/period", "2500000"}, {"/pwmchip0/pwm2/duty_cycle", "1000000"},
      {"/pwmchip0/pwm2/enable", "1"},       {"/pwmchip0/export", "5"},
      {"/pwmchip0/pwm5/period", "2500000"}, {"/pwmchip0/pwm5/duty_cycle", "1100000"},
      {"/pwmchip0/pwm5/enable", "1"}};
  EXPECT_EQ(writes, expected);
  writes.clear();
  const double pulses[2] = {1234.567, 1999.9996};
  ASSERT_TRUE(driver.write(pulses, 2, output::kAllArmed));
  EXPECT_EQ(tree.read(2, "duty_cycle"), "1234567");
  EXPECT_EQ(tree.read(5, "duty_cycle"), "2000000");
  ASSERT_EQ(writes.size(), 2u);  // duty_cycle only, once set up
  const double disarmed[2] = {1000.0, 1100.0};
  ASSERT_TRUE(driver.write(disarmed, 2, 0));
  EXPECT_EQ(tree.read(2, "duty_cycle"), "1000000");  // a shorter value leaves no tail
  EXPECT_FALSE(driver.write(disarmed, 1, 0));        // wrong count
}

TEST(SysfsPwm, AMissingChipOrAChannelThatNeverAppearsIsAnErrorNamingThePath) {
  FakePwmTree tree;
  config::SysfsPwm s;
  s.root = tree.root;
  s.chip = 3;
  s.channels = {0};
  try {
    output::SysfsPwmDriver driver(s, 2500.0, {1000.0});
    ADD_FAILURE() << "no pwmchip3";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("pwmchip3"), std::string::npos);
  }
  s.chip = 0;
  try {
    output::SysfsPwmDriver driver(s, 2500.0, {1000.0}, {}, 0.05);
    ADD_FAILURE() << "pwm0 never appeared";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("pwm0 did not appear"), std::string::npos) << e.what();
  }
}

// The firmware's end of a pseudo-terminal: frames the driver sent, and
// reports written back.
struct PtyPair {
  PtyPair() {
    master = posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK);
    grantpt(master);
    unlockpt(master);
    char name[128];
    ptsname_r(master, name, sizeof name);
    device = name;
  }
  ~PtyPair() { ::close(master); }
  // The frames that came through, waiting (bounded) until `want` did:
  // the tty layer hands bytes over a moment after they were written.
  std::vector<mm_link_frame> frames(std::size_t want, int wait_ms = 1000) {
    std::vector<mm_link_frame> out;
    std::uint8_t buf[512];
    for (int waited = 0; waited <= wait_ms && out.size() < want; ++waited) {
      ssize_t n;
      while ((n = ::read(master, buf, sizeof buf)) > 0) {
        for (ssize_t i = 0; i < n; ++i) {
          mm_link_frame f{};
          if (mm_link_feed(&parser, buf[i], &f) != 0) out.push_back(f);
        }
      }
      if (out.size() < want) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    return out;
  }
  void send(const std::uint8_t* buf, std::size_t n) {
    ASSERT_EQ(::write(master, buf, n), static_cast<ssize_t>(n));
  }
  void report(std::uint8_t flags, std::uint32_t session = 0x10001, std::uint32_t last = 0) {
    mm_link_report r{};
    r.frames = 7;
    r.flags = flags;
    r.session = session;
    r.last_sequence = last;
    r.version = MM_LINK_VERSION;
    std::uint8_t buf[MM_LINK_MAX_FRAME];
    const std::size_t n = mm_link_encode_report(&r, 1, buf);
    ASSERT_EQ(::write(master, buf, n), static_cast<ssize_t>(n));
  }
  int master = -1;
  std::string device;
  mm_link_parser parser = [] {
    mm_link_parser p;
    mm_link_parser_init(&p);
    return p;
  }();
};

// Services the driver until it has heard the chip's first report (bounded):
// false if it never did or the device was lost.
bool first_report_heard(output::SerialPulseDriver& driver) {
  for (int i = 0; i < 1000 && driver.reports() < 1; ++i) {
    if (!driver.service(0.0)) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return driver.reports() >= 1;
}

// Four motors in DShot600 at 1 kHz, 1000..2000 us.
output::SerialPulseSettings dshot_four() {
  output::SerialPulseSettings s;
  s.period_us = 1000;
  s.min_us = 1000;
  s.max_us = 2000;
  s.disarmed_us = {1000, 1000, 1000, 1000};
  s.protocol = MM_LINK_PROTOCOL_DSHOT600;
  return s;
}

TEST(SerialPulses, ConfiguresTheFirmwareSendsHalfMicrosecondsAndReconfiguresAfterAReset) {
  PtyPair pty;
  output::SerialPulseSettings s;
  s.period_us = 2500;
  s.link_timeout_ms = 100;
  s.min_us = 1000;
  s.max_us = 2000;
  s.disarmed_us = {1000, 1000, 1000, 1000};
  output::SerialPulseDriver driver(output::open_serial_port(pty.device, 250000), s);
  const double pulses[4] = {1234.3, 1500, 1750.74, 1999.9};
  const auto serve_until_report = [&](std::uint64_t reports, double now) {
    for (int i = 0; i < 1000 && driver.reports() < reports; ++i) {
      ASSERT_TRUE(driver.service(now));
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    ASSERT_EQ(driver.reports(), reports);
  };
  // Before the firmware's first report nothing goes: it has not named its
  // session, and a frame for no session would be refused.
  ASSERT_TRUE(driver.write(pulses, 4, output::kAllArmed));
  ASSERT_TRUE(driver.service(0.0));
  EXPECT_TRUE(pty.frames(1, 50).empty());
  EXPECT_NE(driver.describe().find("1 held"), std::string::npos) << driver.describe();
  // An unconfigured chip's report names its session: the configuration
  // goes at once, for that session, then the pulses.
  pty.report(0, 0x20001, 0);
  serve_until_report(1, 0.0);
  EXPECT_EQ(driver.session(), 0x20001u);
  ASSERT_TRUE(driver.write(pulses, 4, output::kAllArmed));
  std::vector<mm_link_frame> got = pty.frames(2);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].type, MM_LINK_CONFIG);
  EXPECT_EQ(got[0].u.config.session, 0x20001u);
  EXPECT_EQ(got[0].u.config.sequence, 1u);
  EXPECT_EQ(got[0].u.config.period_us, 2500);
  EXPECT_EQ(got[0].u.config.count, 4);
  EXPECT_EQ(got[1].type, MM_LINK_PULSES);
  EXPECT_EQ(got[1].u.pulses.session, 0x20001u);
  EXPECT_EQ(got[1].u.pulses.sequence, 2u);
  EXPECT_EQ(got[1].u.pulses.armed, 0xF);  // every channel
  // A motor test: the one channel armed, bits beyond the count dropped.
  ASSERT_TRUE(driver.write(pulses, 4, 0xF4U));
  const std::vector<mm_link_frame> one = pty.frames(1);
  ASSERT_EQ(one.size(), 1u);
  EXPECT_EQ(one[0].u.pulses.armed, 0x4);
  EXPECT_EQ(got[1].u.pulses.pulse_hus[0], 2469);  // 1234.5 us: the nearest half microsecond
  EXPECT_EQ(got[1].u.pulses.pulse_hus[2], 3501);
  EXPECT_EQ(got[1].u.pulses.pulse_hus[3], 4000);
  // A configured chip's report: nothing more within the second.
  pty.report(MM_LINK_FLAG_CONFIGURED, 0x20001, 2);
  serve_until_report(2, 0.2);
  EXPECT_TRUE(pty.frames(1, 50).empty());
  EXPECT_NE(driver.describe().find("7 frames taken"), std::string::npos) << driver.describe();
  // The chip's link timed out: a new session, frames go on in it from the
  // last sequence the chip took.
  pty.report(MM_LINK_FLAG_CONFIGURED | MM_LINK_FLAG_TIMED_OUT, 0x20002, 0);
  serve_until_report(3, 0.3);
  ASSERT_TRUE(driver.write(pulses, 4, 0));
  got = pty.frames(1);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].u.pulses.session, 0x20002u);
  EXPECT_EQ(got[0].u.pulses.sequence, 1u);
  EXPECT_EQ(driver.sessions(), 2u);
  // A report from a chip that lost its configuration (a watchdog reset):
  // the configuration goes again at once, within the second.
  pty.report(0, 0x30001, 0);
  serve_until_report(4, 0.4);
  got = pty.frames(1);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].type, MM_LINK_CONFIG);
  EXPECT_EQ(got[0].u.config.session, 0x30001u);
  // The periodic configuration, once a second.
  ASSERT_TRUE(driver.service(1.5));
  got = pty.frames(1);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].type, MM_LINK_CONFIG);
}

// The host's sequence far ahead of the last the chip took in the same
// session (frames the chip refused piled up: here, a report that moved it
// to 40000, then one saying the chip took only up to 2): more than half of
// the largest step the chip accepts ahead, it goes back to the chip's last,
// or the chip would refuse every frame from then on.
TEST(SerialPulses, AHostFarAheadOfTheChipGoesBackToItsLastSequence) {
  PtyPair pty;
  output::SerialPulseSettings s;
  s.period_us = 2500;
  s.min_us = 1000;
  s.max_us = 2000;
  s.disarmed_us = {1000, 1000, 1000, 1000};
  output::SerialPulseDriver driver(output::open_serial_port(pty.device, 250000), s);
  const double pulses[4] = {1200, 1300, 1400, 1500};
  const auto serve_until_report = [&](std::uint64_t reports, double now) {
    for (int i = 0; i < 1000 && driver.reports() < reports; ++i) {
      ASSERT_TRUE(driver.service(now));
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    ASSERT_EQ(driver.reports(), reports);
  };
  constexpr std::uint32_t kSession = 0x20001;
  constexpr std::uint32_t kAhead = 40000;
  static_assert(kAhead > MM_LINK_MAX_SEQUENCE_STEP / 2 && kAhead < MM_LINK_MAX_SEQUENCE_STEP);
  pty.report(MM_LINK_FLAG_CONFIGURED, kSession, 0);
  serve_until_report(1, 0.0);
  pty.report(MM_LINK_FLAG_CONFIGURED, kSession, kAhead);
  serve_until_report(2, 0.1);
  pty.frames(8, 50);  // whatever went before
  ASSERT_TRUE(driver.write(pulses, 4, output::kAllArmed));
  std::vector<mm_link_frame> got = pty.frames(1);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].u.pulses.sequence, kAhead + 1);  // up to what the chip took
  pty.report(MM_LINK_FLAG_CONFIGURED, kSession, 2);
  serve_until_report(3, 0.2);
  ASSERT_TRUE(driver.write(pulses, 4, output::kAllArmed));
  got = pty.frames(1);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].u.pulses.session, kSession);
  EXPECT_EQ(got[0].u.pulses.sequence, 3u);
}

// Values faster than the output's share of the wire (a loop rate above
// some 580 Hz for four motors at 250000 baud): after one frame of credit, a
// frame per share of time, the newest waiting in place of older ones and
// sent when its time comes; a change of arming never waits. Without the pacing every write went to
// the kernel's queue: the pins followed tens of milliseconds late.
TEST(SerialPulses, FramesFasterThanTheWireWaitNewestFirstAndArmingNeverWaits) {
  PtyPair pty;
  output::SerialPulseSettings s = dshot_four();
  output::SerialPulseDriver driver(output::open_serial_port(pty.device, 250000), s);
  pty.report(MM_LINK_FLAG_CONFIGURED, 0x40001, 0);
  ASSERT_TRUE(first_report_heard(driver));
  ASSERT_EQ(pty.frames(1).size(), 1u);  // the configuration
  // The first frame arms (never waits); twenty more as fast as they come.
  constexpr double kFrameS = (7.0 + MM_LINK_PULSES_BODY(4)) * 10.0 / 250000.0 / output::kWireShare;
  constexpr int kWrites = 20;
  const double start = bus::monotonic_s();
  double pulses[4] = {1100, 1100, 1100, 1100};
  for (int k = 0; k < kWrites; ++k) {
    pulses[0] = 1100.0 + k;
    ASSERT_TRUE(driver.write(pulses, 4, output::kAllArmed));
  }
  const double elapsed = bus::monotonic_s() - start;
  EXPECT_TRUE(std::isfinite(driver.waiting_until_s()));
  // Once the wire is free, the newest goes.
  while (bus::monotonic_s() < driver.waiting_until_s()) {
  }
  driver.send_waiting();
  EXPECT_FALSE(std::isfinite(driver.waiting_until_s()));
  // A disarm goes at once, busy wire or not.
  ASSERT_TRUE(driver.write(pulses, 4, 0));
  const std::vector<mm_link_frame> got = pty.frames(kWrites + 1, 200);
  // At most one frame per frame time while writing (plus the first and the
  // one the credit lets go at once), then the one that waited, then the
  // disarm.
  const auto on_wire_while_writing = static_cast<std::size_t>(elapsed / kFrameS) + 2;
  ASSERT_GE(got.size(), 3u);
  EXPECT_LE(got.size(), on_wire_while_writing + 2) << "written in " << elapsed * 1e3 << " ms";
  EXPECT_EQ(got.front().u.pulses.pulse_hus[0], 2200);
  EXPECT_EQ(got[got.size() - 2].u.pulses.pulse_hus[0], 2 * (1100 + kWrites - 1)) << "the newest";
  EXPECT_EQ(got.back().u.pulses.armed, 0);
  EXPECT_EQ(driver.superseded(), static_cast<std::uint64_t>(kWrites + 1 - got.size()));
  EXPECT_NE(driver.describe().find("replaced by a newer one"), std::string::npos);
}

TEST(SerialPulses, ANonSerialDeviceIsRefusedByName) {
  try {
    output::open_serial_port("/dev/null", 250000);
    ADD_FAILURE() << "/dev/null taken as a serial port";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/null"), std::string::npos);
  }
}

// A KISS telemetry request goes in the next PULSES frame, once; the driver
// says which channel it asked and when; servo PWM cannot ask.
TEST(SerialPulses, ATelemetryRequestGoesInTheNextFrameOnce) {
  PtyPair pty;
  output::SerialPulseSettings s = dshot_four();
  s.baud = 2e6;  // no pacing in the way
  output::SerialPulseDriver driver(output::open_serial_port(pty.device, 250000), s);
  pty.report(MM_LINK_FLAG_CONFIGURED, 0x50001, 0);
  ASSERT_TRUE(first_report_heard(driver));
  ASSERT_EQ(pty.frames(1).size(), 1u);  // the configuration
  EXPECT_FALSE(driver.ask_telemetry(4)) << "no channel 4 on four motors";
  ASSERT_TRUE(driver.ask_telemetry(2));
  const double widths[4] = {1100, 1200, 1300, 1400};
  double at = -1.0;
  EXPECT_EQ(driver.take_asked(at), -1) << "asked before any frame went";
  ASSERT_TRUE(driver.write(widths, 4, output::kAllArmed));
  EXPECT_EQ(driver.take_asked(at), 2);
  EXPECT_GT(at, 0.0);
  EXPECT_EQ(driver.take_asked(at), -1) << "reported once";
  ASSERT_TRUE(driver.write(widths, 4, output::kAllArmed));
  const std::vector<mm_link_frame> got = pty.frames(2);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].u.pulses.telemetry, 3) << "channel 2 asked (+1)";
  EXPECT_EQ(got[1].u.pulses.telemetry, 0) << "the next frame asks nothing";

  PtyPair pwm_pty;
  s.protocol = MM_LINK_PROTOCOL_PWM;
  s.period_us = 2500;
  output::SerialPulseDriver pwm(output::open_serial_port(pwm_pty.device, 250000), s);
  EXPECT_FALSE(pwm.ask_telemetry(0)) << "servo PWM cannot ask";
}

// Bidirectional DShot: the CONFIG carries the flag; each TELEMETRY frame's
// readings come out of take_erpm() as eRPM (60e6 / period), a missing reply
// as NaN and counted, the largest period (a stopped motor) as 0; on the
// bus a frame names only the motors whose reply was decoded.
TEST(SerialPulses, BidirectionalDshotRepliesBecomeErpmAndEscTelemetry) {
  PtyPair pty;
  output::SerialPulseSettings s;
  s.period_us = 1250;
  s.min_us = 1000;
  s.max_us = 2000;
  s.disarmed_us = {1000, 1000, 1000, 1000};
  s.protocol = MM_LINK_PROTOCOL_DSHOT600;
  s.bidirectional = true;
  output::SerialPulseDriver driver(output::open_serial_port(pty.device, 250000), s);
  pty.report(0, 0x30001, 0);
  ASSERT_TRUE(first_report_heard(driver));
  const std::vector<mm_link_frame> config = pty.frames(1);
  ASSERT_EQ(config.size(), 1u);
  EXPECT_EQ(config[0].u.config.protocol,
            MM_LINK_PROTOCOL_DSHOT600 | MM_LINK_PROTOCOL_BIDIRECTIONAL);

  mm_link_telemetry t{};
  t.first = 65535;  // the frame counter wraps: nothing depends on it
  t.readings = 2;
  t.count = 4;
  const std::uint16_t periods[2][4] = {
      {2000, MM_LINK_NO_REPLY, 511u << 7, 300},
      {MM_LINK_NO_REPLY, MM_LINK_NO_REPLY, MM_LINK_NO_REPLY, MM_LINK_NO_REPLY}};
  for (int r = 0; r < 2; ++r)
    for (int c = 0; c < 4; ++c) t.period_us[r][c] = periods[r][c];
  std::uint8_t buf[MM_LINK_MAX_FRAME];
  const std::size_t n = mm_link_encode_telemetry(&t, 5, buf);
  ASSERT_EQ(n, 7u + MM_LINK_TELEMETRY_BODY(2u, 4u));
  pty.send(buf, n);
  std::vector<output::PulseDriver::ErpmReading> got;
  for (int i = 0; i < 1000 && got.size() < 2; ++i) {
    ASSERT_TRUE(driver.service(0.0));
    for (auto& r : driver.take_erpm()) got.push_back(std::move(r));
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  ASSERT_EQ(got.size(), 2u);
  EXPECT_DOUBLE_EQ(got[0].erpm[0], 30000.0);
  EXPECT_TRUE(std::isnan(got[0].erpm[1]));
  EXPECT_DOUBLE_EQ(got[0].erpm[2], 0.0);
  EXPECT_DOUBLE_EQ(got[0].erpm[3], 200000.0);
  EXPECT_EQ(driver.replies_decoded(), 3u);
  EXPECT_EQ(driver.replies_missed(), 5u);

  motormix::esc_telemetry_t msg;
  ASSERT_TRUE(output::fill_erpm_message(got[0], 1234, msg));
  EXPECT_EQ(msg.utime, 1234);
  ASSERT_EQ(msg.count, 3);
  EXPECT_EQ(msg.motor, (std::vector<std::int8_t>{1, 3, 4}));
  EXPECT_FLOAT_EQ(msg.erpm[0], 30000.0F);
  EXPECT_TRUE(std::isnan(msg.rpm[0]));
  EXPECT_TRUE(std::isnan(msg.current_a[2]));
  EXPECT_FALSE(output::fill_erpm_message(got[1], 1234, msg)) << "no reply in that frame";
}

}  // namespace
}  // namespace motormix::test
