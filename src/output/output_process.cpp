#include "output/output_process.hpp"

#include "output/erpm_telemetry.hpp"
#include "output/esc_command_check.hpp"
#include "output/output_gate.hpp"
#include "output/pulse_drivers.hpp"
#include "output/serial_port.hpp"
#include "output/telemetry_requests.hpp"

#include "bus/clock.hpp"
#include "bus/policy_or_error.hpp"
#include "bus/process.hpp"
#include "bus/receive.hpp"
#include "bus/sealed_publisher.hpp"
#include "bus/shutdown_signals.hpp"
#include "realtime/realtime.hpp"

#include <motormix/config/security.hpp>
#include <motormix/esc_command_t.hpp>
#include <motormix/esc_telemetry_t.hpp>
#include <motormix/motor_pwm_t.hpp>
#include <motormix/output_status_t.hpp>

#include <lcm/lcm-cpp.hpp>

#include <sys/timerfd.h>
#include <unistd.h>
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <optional>
#include <thread>
#include <utility>
#include <vector>

namespace motormix::output {

namespace {

constexpr double kTickS = 0.005;       // the gate is checked this often without input
constexpr double kKeepAliveS = 0.020;  // and the hardware written at least this often
constexpr double kStatusEveryS = 5.0;
constexpr double kReopenEveryS = 0.5;  // a lost serial device is tried again this often
// LCM's receive queue keeps 30 messages by default and drops the newest
// when full: for the process that moves the pins the newest is the one that
// matters. bus::kQueueCapacity is deep enough for any burst, and the queue
// is drained at every wake-up (bounded by bus::kMaxMessagesPerDrain, so a
// flood cannot starve the failsafe timer).

using bus::monotonic_s;
using bus::wall_us;

struct TelemetryWire {
  config::TelemetryPort port;
  int fd = -1;
  KissTelemetryParser parser;
};

class OutputNode {
 public:
  OutputNode(const config::Config& config, signing::Policy policy, lcm::LCM& lcm,
             PulseDriver& driver, std::ostream& log)
      : config_(config),
        policy_(std::move(policy)),
        lcm_(lcm),
        publisher_(lcm, policy_),
        driver_(&driver),
        log_(log),
        gate_(ranges_of(config), config.hardware.motor_pwm_timeout_s,
              BringupLimits{config.motor_test.enabled, config.motor_test.max_throttle,
                            config.motor_test.max_seconds}),
        values_(static_cast<std::size_t>(config.motors())),
        requests_(wired_motors(config.hardware), kKissAnswerWindowS) {}

  // KISS telemetry: the request that went is noted, and the next wire asked
  // for in the frames to come (one request open on the driver at a time).
  void telemetry_turn() {
    if (driver_ == nullptr || requests_.empty()) return;
    double at_s = 0.0;
    const int asked = driver_->take_asked(at_s);
    if (asked >= 0) {
      requests_.asked(asked, at_s);
      ask_open_ = false;
    }
    if (!ask_open_) ask_open_ = driver_->ask_telemetry(requests_.next());
  }

  void subscribe() {
    lcm_.subscribe(config_.channels.motor_pwm, &OutputNode::on_motor_pwm, this)
        ->setQueueCapacity(bus::kQueueCapacity);
    lcm_.subscribe(config_.channels.esc_command, &OutputNode::on_esc_command, this)
        ->setQueueCapacity(bus::kQueueCapacity);
  }

  // Decides and writes when something changed or the hardware is due.
  void step(double now, bool message) {
    telemetry_turn();
    const GateState state = gate_.decide(now, values_.data());
    if (message || state != state_ || now - last_write_s_ >= kKeepAliveS) {
      // No device (lost, being reopened): nothing to write, the chip has
      // disarmed on its own.
      const std::uint32_t mask = state == GateState::kArmed       ? kAllArmed
                                 : state == GateState::kMotorTest ? gate_.bringup()
                                                                  : 0U;
      written_armed_ = driver_ != nullptr ? mask : 0U;
      if (driver_ != nullptr && !driver_->write(values_.data(), gate_.outputs(), mask))
        ++write_failures_;
      last_write_s_ = now;
    }
    if (state != state_) {
      log_ << "motormix output: " << to_string(state_) << " -> " << to_string(state) << std::endl;
      state_ = state;
    }
  }

  // The device was lost (null) or opened again: writes go to `driver`.
  void set_driver(PulseDriver* driver) {
    if (driver != nullptr && driver_ == nullptr) ++reopened_;
    driver_ = driver;
    ask_open_ = false;  // a new driver has no request of the old one's
    if (driver_ == nullptr) written_armed_ = 0;
  }

  // Writes the newest message taken since the last call (on_motor_pwm),
  // once the bus is drained.
  void write_taken(double now) {
    if (!taken_) return;
    taken_ = false;
    step(now, true);
  }

  void write_disarmed() {
    for (int i = 0; i < gate_.outputs(); ++i)
      values_[static_cast<std::size_t>(i)] = gate_.range(i).disarmed;
    if (driver_ != nullptr) driver_->write(values_.data(), gate_.outputs(), 0U);
    written_armed_ = 0;
  }

  void status_line() {
    const GateCounters& c = gate_.counters();
    log_ << "motormix output: " << to_string(state_) << "; motor_pwm_t: " << c.accepted
         << " taken, " << bus::describe(refusals_) << "; " << c.wrong_size << " array size, "
         << c.out_of_range << " out of range, " << c.not_finite << " not finite, " << c.clamped
         << " values clamped, " << c.stale_events << " times stale, " << c.bringup_refused
         << " motor tests refused; ";
    if (policy_.signs()) {
      const signing::PolicyCounts& sc = policy_.counts();
      log_ << "signatures: " << sc.signed_accepted << " verified, " << sc.unsigned_accepted
           << " unsigned taken, refused " << sc.rejected_unsigned << " unsigned, "
           << sc.rejected_bad_signature << " bad, " << sc.rejected_replayed << " replayed, "
           << sc.rejected_stale + sc.rejected_other << " stale; ";
    }
    if (!requests_.empty()) {
      const TelemetryRequests::Counts& t = requests_.counts();
      log_ << "KISS telemetry: " << t.asked << " asked, " << t.answered << " answered, "
           << t.unanswered << " unanswered, " << t.unasked << " unasked; ";
    }
    log_ << write_failures_ << " hardware writes failed; "
         << (driver_ != nullptr ? driver_->describe() : std::string("device lost, reopening"))
         << std::endl;
  }

  // output_status_t: what the pins carry and why, the counts, the chip's report.
  void publish_status() {
    const GateCounters& c = gate_.counters();
    motormix::output_status_t msg{};
    msg.utime = wall_us();
    msg.driver = config_.hardware.driver == config::HardwareDriver::kSerial
                     ? motormix::output_status_t::DRIVER_SERIAL
                     : motormix::output_status_t::DRIVER_SYSFS;
    switch (state_) {
      case GateState::kStarting:
        msg.pins = motormix::output_status_t::PINS_STARTING;
        break;
      case GateState::kArmed:
        // Armed by the gate, but the last write was disarmed (on the way out).
        msg.pins = written_armed_ != 0 ? motormix::output_status_t::PINS_ARMED
                                       : motormix::output_status_t::PINS_DISARMED;
        break;
      case GateState::kMotorTest:
        msg.pins = written_armed_ != 0 ? motormix::output_status_t::PINS_MOTOR_TEST
                                       : motormix::output_status_t::PINS_DISARMED;
        break;
      case GateState::kDisarmed:
        msg.pins = motormix::output_status_t::PINS_DISARMED;
        break;
      case GateState::kStale:
        msg.pins = motormix::output_status_t::PINS_STALE;
        break;
    }
    msg.num_motors = gate_.outputs();
    for (int i = 0; i < gate_.outputs() && i < 16; ++i)
      msg.pulse[i] = static_cast<float>(values_[static_cast<std::size_t>(i)]);
    const auto count = [](std::uint64_t v) { return static_cast<std::int64_t>(v); };
    msg.taken = count(c.accepted);
    msg.refused_signature = count(refusals_.signature);
    msg.refused_malformed = count(refusals_.malformed());
    msg.refused_wrong_size = count(c.wrong_size);
    msg.refused_not_finite = count(c.not_finite);
    msg.refused_out_of_range = count(c.out_of_range);
    msg.clamped = count(c.clamped);
    msg.stale_events = count(c.stale_events);
    msg.refused_bringup = count(c.bringup_refused);
    msg.write_failures = count(write_failures_);
    msg.telemetry_frames = count(telemetry_frames_);
    msg.esc_commands_sent = count(commands_sent_);
    msg.esc_commands_refused = count(commands_refused_);
    msg.device_open = driver_ != nullptr;
    msg.device_reopened = static_cast<std::int32_t>(reopened_);
    if (const std::optional<FirmwareReport> r =
            driver_ != nullptr ? driver_->firmware_report() : std::nullopt) {
      msg.firmware_report = true;
      msg.firmware_frames = count(r->frames);
      msg.firmware_crc_errors = count(r->crc_errors);
      msg.firmware_malformed = count(r->malformed);
      msg.firmware_link_timeouts = static_cast<std::int32_t>(r->link_timeouts);
      msg.firmware_watchdog_resets = static_cast<std::int32_t>(r->watchdog_resets);
      msg.firmware_rejected = static_cast<std::int32_t>(r->rejected);
      msg.firmware_flags = static_cast<std::int8_t>(r->flags);
    }
    publisher_.publish(config_.channels.output_status, msg);
  }

  // Bidirectional DShot: each frame's eRPM replies as they come.
  void publish_erpm(const PulseDriver::ErpmReading& reading) {
    motormix::esc_telemetry_t msg;
    if (!fill_erpm_message(reading, wall_us(), msg)) return;
    publisher_.publish(config_.channels.esc_telemetry, msg);
    ++telemetry_frames_;
  }

  // A KISS reading arrived at `now` (monotonic s): stamped when its request
  // went (the ESC measured it then); one nobody asked for, when it came.
  void publish_telemetry(const TelemetryWire& wire, const KissReading& r, double now) {
    const std::optional<double> asked_s = requests_.answered(wire.port.motor, now);
    motormix::esc_telemetry_t msg;
    fill_kiss_message(wire.port.motor, r,
                      wall_us() - (asked_s ? static_cast<std::int64_t>((now - *asked_s) * 1e6) : 0),
                      msg);
    publisher_.publish(config_.channels.esc_telemetry, msg);
    ++telemetry_frames_;
  }

 private:
  // Nothing here throws (bus::receive): a message the signing policy
  // refuses is counted there, one that is not a whole motor_pwm_t in
  // refusals_, and neither reaches the gate.
  void on_motor_pwm(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    if (bus::receive(policy_, rbuf, channel, wall_us(), pwm_msg_, refusals_) != bus::Refusal::kNone)
      return;
    // Taken by the gate now; written once the bus is drained (write_taken):
    // after a stall, the messages that queued meanwhile are old, and writing
    // each would put a backlog of frames on the serial line ahead of the
    // newest (4 ms for six at 250000 baud).
    if (gate_.accept(pwm_msg_.pwm.data(), pwm_msg_.num_motors, pwm_msg_.armed,
                     static_cast<std::uint32_t>(pwm_msg_.bringup_motors), monotonic_s()))
      taken_ = true;
  }

  // A DShot special command: to the firmware only while nothing is armed
  // (the gate's state and the last write both), whole and in range;
  // counted and logged either way.
  void on_esc_command(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    // Its own refusal counts: refused_malformed and refused_signature are
    // motor_pwm_t's; a command that is not whole, or not signed under
    // require, is a refused command.
    if (bus::receive(policy_, rbuf, channel, wall_us(), command_msg_, command_refusals_) !=
        bus::Refusal::kNone) {
      ++commands_refused_;
      return;
    }
    const esc_command_t& m = command_msg_;
    const std::uint32_t motors = static_cast<std::uint32_t>(m.motors);
    const bool disarmed = (state_ == GateState::kDisarmed || state_ == GateState::kStale ||
                           state_ == GateState::kStarting) &&
                          written_armed_ == 0;
    const EscCommandRequest request{m.command, m.repeat, motors};
    const char* why =
        esc_command_refusal(config_.hardware.protocol, request, gate_.outputs(), disarmed);
    if (why == nullptr &&
        (driver_ == nullptr || !driver_->command(static_cast<std::uint8_t>(m.command), motors,
                                                 static_cast<std::uint8_t>(m.repeat)))) {
      why = "the firmware cannot take it now (no device, or no report from it yet)";
    }
    ++(why != nullptr ? commands_refused_ : commands_sent_);
    command_log_.line(log_, monotonic_s(), request, why);
  }

  const config::Config& config_;
  signing::Policy policy_;
  lcm::LCM& lcm_;
  bus::SealedPublisher publisher_;  // signs with policy_ when it signs
  PulseDriver* driver_;             // null while a lost device is being reopened
  std::ostream& log_;
  OutputGate gate_;
  std::vector<double> values_;
  GateState state_ = GateState::kStarting;
  double last_write_s_ = -1e9;
  motormix::motor_pwm_t pwm_msg_{};  // decoded into, its arrays reused
  motormix::esc_command_t command_msg_{};
  bus::Refusals command_refusals_;
  std::uint64_t commands_sent_ = 0, commands_refused_ = 0;
  EscCommandLog command_log_;
  bus::Refusals refusals_;
  bool taken_ = false;  // a message taken and not yet written
  std::uint64_t write_failures_ = 0;
  std::uint64_t telemetry_frames_ = 0;
  TelemetryRequests requests_;
  bool ask_open_ = false;            // a request waits on the driver for a frame
  std::uint32_t written_armed_ = 0;  // the channels the last write armed
  std::uint64_t reopened_ = 0;       // lost devices opened again
};

}  // namespace

int run_output(const config::Config& config, const OutputOptions& options, std::ostream& log) {
  if (config.hardware.driver == config::HardwareDriver::kNone) {
    log << "motormix output: the configuration has no hardware driver (hardware.driver: none); "
           "see docs/wiring-it-to-motors.md"
        << std::endl;
    return 1;
  }
  // From here on SIGTERM is read in the loop; the bus opened, or one
  // message and exit status 1 before any pin is touched.
  bus::Process process("motormix output", options.lcm_url, log);
  if (!process.good()) return 1;
  lcm::LCM& lcm = process.lcm();
  bus::ShutdownSignals& signals = process.signals();
  // Before any pulse: a bad key file stops here.
  std::optional<signing::Policy> policy = bus::policy_or_error(config, "output", log);
  if (!policy) return 1;
  std::unique_ptr<PulseDriver> driver;
  std::vector<TelemetryWire> wires;
  try {
    driver = make_driver(config);  // disarmed pulses from here on
    for (const config::TelemetryPort& p : config.hardware.telemetry) {
      TelemetryWire w;
      w.port = p;
      w.fd = open_serial_port(p.device, p.baud);
      wires.push_back(std::move(w));
    }
  } catch (const std::exception& e) {
    log << "motormix output: " << e.what() << std::endl;
    return 1;
  }
  const auto close_wires = [&] {
    for (TelemetryWire& w : wires) ::close(w.fd);
  };
  OutputNode node(config, std::move(*policy), lcm, *driver, log);
  // Subscribed before the first disarmed write: nothing is handled until
  // the loop below, and a publisher that sees the pins disarmed knows its
  // messages are heard from then on.
  if (!options.disarm_only) node.subscribe();
  node.write_disarmed();
  log << "motormix output: " << config::to_string(config.hardware.driver) << " driver, "
      << config.motors() << " motors at " << config.hardware.pulse_rate_hz << " Hz; disarmed until "
      << config.channels.motor_pwm << " says armed (stale after "
      << config.hardware.motor_pwm_timeout_s * 1e3 << " ms)" << std::endl;
  log << "motormix output: " << config::describe(config.security) << std::endl;
  if (options.disarm_only) {
    // Twice, a period apart, so a frame lost on the wire does not matter.
    driver->service(monotonic_s());
    std::this_thread::sleep_for(std::chrono::duration<double>(2.0 / config.hardware.pulse_rate_hz));
    node.write_disarmed();
    close_wires();
    return 0;
  }

  const int timer_fd = timerfd_create(CLOCK_MONOTONIC, TFD_CLOEXEC);
  itimerspec spec{};
  spec.it_interval.tv_nsec = static_cast<long>(kTickS * 1e9);
  spec.it_value.tv_nsec = static_cast<long>(kTickS * 1e9);
  if (timer_fd < 0 || timerfd_settime(timer_fd, 0, &spec, nullptr) != 0) {
    log << "motormix output: cannot create the timer descriptor: " << std::strerror(errno)
        << std::endl;
    close_wires();
    return 1;
  }
  // realtime: as `motormix run` takes it: requests, each refusal logged,
  // what was granted read back (after LCM's threads have started).
  const realtime::RealtimeGranted granted = realtime::apply_realtime(config.realtime, log);
  log << "motormix output: scheduling: " << realtime::describe(granted) << std::endl;
  const std::size_t tick = process.watch(timer_fd);
  std::vector<std::size_t> wire_index;
  for (const TelemetryWire& w : wires) wire_index.push_back(process.watch(w.fd));
  const double start = monotonic_s();
  double next_reopen = start;
  int reopen_failures = 0;
  double next_status = start + kStatusEveryS;
  // output_status_t at the configuration's status rate, from the first tick.
  const double status_period = 1.0 / config.status_rate_hz;
  double next_published = start;
  int code = 0;
  while (true) {
    // Woken for a frame waiting for the wire too (the serial driver's
    // pacing), not only by the bus, the tick or a signal.
    const double wake_s =
        driver != nullptr ? driver->waiting_until_s() : std::numeric_limits<double>::infinity();
    const std::int64_t timeout_ns =
        std::isfinite(wake_s)
            ? static_cast<std::int64_t>(std::max(0.0, wake_s - monotonic_s()) * 1e9)
            : -1;
    const bus::Woke woke = process.wait_ns(timeout_ns);
    if (woke.error != 0) {
      log << "motormix output: poll failed: " << std::strerror(woke.error) << std::endl;
      code = 1;
      break;
    }
    if (woke.signal) {
      log << "motormix output: signal " << signals.last_signal()
          << ", writing disarmed pulses and exiting" << std::endl;
      break;
    }
    if (woke.bus) bus::drain(lcm);
    const double now = monotonic_s();
    node.write_taken(now);
    if (driver != nullptr) driver->send_waiting();
    node.telemetry_turn();
    if (woke.own[tick]) {
      std::uint64_t expirations = 0;
      [[maybe_unused]] const ssize_t got = read(timer_fd, &expirations, sizeof expirations);
      node.step(now, false);
      const bool serviced = driver == nullptr || driver->service(now);
      if (driver != nullptr)
        for (const PulseDriver::ErpmReading& r : driver->take_erpm()) node.publish_erpm(r);
      if (!serviced) {
        // The chip disarms on its own after its link timeout; reopened, it
        // is configured again before its first pulses.
        log << "motormix output: lost " << config.hardware.serial.device << " ("
            << driver->describe() << "); the firmware disarms on its own after "
            << config.hardware.serial.link_timeout_s * 1e3 << " ms; reopening every "
            << kReopenEveryS << " s" << std::endl;
        node.set_driver(nullptr);
        driver.reset();
        next_reopen = now;
        reopen_failures = 0;
      }
      if (driver == nullptr && now >= next_reopen) {
        try {
          driver = make_driver(config);
          node.set_driver(driver.get());
          node.write_disarmed();
          log << "motormix output: reopened " << config.hardware.serial.device
              << " and configured the firmware again" << std::endl;
        } catch (const std::exception& e) {
          // Once, then every tenth try: a device that stays away is no news.
          if (reopen_failures++ % 10 == 0) log << "motormix output: " << e.what() << std::endl;
          next_reopen = now + kReopenEveryS;
        }
      }
    }
    for (std::size_t i = 0; i < wires.size(); ++i) {
      if (!woke.own[wire_index[i]]) continue;
      std::uint8_t buf[256];
      const ssize_t n = read(wires[i].fd, buf, sizeof buf);
      const auto t_us = static_cast<std::int64_t>(now * 1e6);
      for (ssize_t k = 0; k < n; ++k) {
        KissReading r;
        if (wires[i].parser.feed(buf[k], t_us, r)) node.publish_telemetry(wires[i], r, now);
      }
    }
    if (now >= next_published) {
      node.publish_status();
      next_published = std::max(next_published + status_period, now - status_period);
    }
    if (now >= next_status) {
      node.status_line();
      next_status = now + kStatusEveryS;
    }
    if (options.max_run_s > 0 && now - start >= options.max_run_s) break;
  }
  for (int i = 0; i < 3 && driver != nullptr; ++i) node.write_disarmed();
  node.status_line();
  node.publish_status();
  close_wires();
  ::close(timer_fd);
  return code;
}

}  // namespace motormix::output
