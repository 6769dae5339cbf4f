#include "output/serial_pulse_driver.hpp"

#include "bus/clock.hpp"

#include <unistd.h>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace motormix::output {

namespace {

std::uint16_t us(double v) {
  return static_cast<std::uint16_t>(std::clamp(std::lround(v), 0L, 65535L));
}

}  // namespace

SerialPulseDriver::SerialPulseDriver(int fd, const SerialPulseSettings& s)
    : fd_(fd), byte_s_(10.0 / std::max(s.baud, 1.0)) {
  config_.protocol = static_cast<std::uint8_t>(
      s.protocol | (s.bidirectional ? MM_LINK_PROTOCOL_BIDIRECTIONAL : 0u));
  config_.period_us = us(s.period_us);
  config_.link_timeout_ms = us(s.link_timeout_ms);
  config_.min_us = us(s.min_us);
  config_.max_us = us(s.max_us);
  config_.count = static_cast<std::uint8_t>(std::min<std::size_t>(s.disarmed_us.size(), 255));
  for (std::size_t i = 0; i < s.disarmed_us.size() && i < MM_LINK_MAX_CHANNELS; ++i)
    config_.disarmed_us[i] = us(s.disarmed_us[i]);
  if (!mm_link_config_valid(&config_)) {
    ::close(fd_);
    throw std::invalid_argument("the pulse firmware cannot take this configuration");
  }
  mm_link_parser_init(&parser_);
}

SerialPulseDriver::~SerialPulseDriver() { ::close(fd_); }

bool SerialPulseDriver::send(const std::uint8_t* bytes, std::size_t n) {
  // A frame goes whole or not at all: the port is non-blocking and a frame
  // is far smaller than its buffer; a partial write would only cost a CRC
  // error at the other end.
  const ssize_t w = ::write(fd_, bytes, n);
  if (w != static_cast<ssize_t>(n)) {
    ++write_failures_;
    // Gone, not busy: a USB adapter pulled out, a pty whose other end closed.
    if (w < 0 &&
        (errno == EIO || errno == ENODEV || errno == ENXIO || errno == EPIPE || errno == EBADF))
      lost_ = true;
    return false;
  }
  const double now = bus::monotonic_s();
  wire_free_s_ = std::max(now, wire_free_s_) + static_cast<double>(n) * byte_s_ / kWireShare;
  return true;
}

void SerialPulseDriver::send_config() {
  if (session_ == 0) return;  // the firmware has not named its session yet
  std::uint8_t buf[MM_LINK_MAX_FRAME];
  config_.session = session_;
  config_.sequence = ++sequence_;
  send(buf, mm_link_encode_config(&config_, buf));
  resend_config_ = false;
}

bool SerialPulseDriver::write(const double* pulse_us, int count, std::uint32_t armed) {
  if (count != config_.count) return false;
  if (session_ == 0) {
    // Nothing can be taken before the firmware's first report: it is
    // unconfigured and makes no pulse; not a failure of the port.
    ++held_;
    return true;
  }
  const auto mask = static_cast<std::uint8_t>(armed & ((1U << count) - 1U));
  if (sent_pulses_ && mask == last_armed_ && bus::monotonic_s() < wire_free_s_ - credit_s_) {
    // The wire is still busy: this one waits, in place of an older one.
    if (waiting_.valid) ++superseded_;
    waiting_.valid = true;
    waiting_.armed = mask;
    waiting_.count = count;
    std::copy(pulse_us, pulse_us + count, waiting_.pulse_us);
    return true;
  }
  waiting_.valid = false;
  return send_pulses(pulse_us, count, mask);
}

bool SerialPulseDriver::send_pulses(const double* pulse_us, int count, std::uint8_t armed) {
  mm_link_pulses p{};
  p.session = session_;
  p.sequence = ++sequence_;
  p.armed = armed;
  p.count = static_cast<std::uint8_t>(count);
  for (int i = 0; i < count; ++i) p.pulse_hus[i] = us(2.0 * pulse_us[i]);
  if (ask_ != 0 && ask_ <= count) p.telemetry = ask_;
  std::uint8_t buf[MM_LINK_MAX_FRAME];
  const std::size_t n = mm_link_encode_pulses(&p, buf);
  credit_s_ = static_cast<double>(n) * byte_s_ / kWireShare;
  const bool ok = send(buf, n);
  if (ok) {
    ++frames_sent_;
    sent_pulses_ = true;
    last_armed_ = armed;
    if (p.telemetry != 0) {
      asked_ = p.telemetry;
      asked_at_s_ = bus::monotonic_s();
      ask_ = 0;
    }
  }
  return ok;
}

bool SerialPulseDriver::ask_telemetry(int channel) {
  if (config_.protocol == MM_LINK_PROTOCOL_PWM || channel < 0 || channel >= config_.count)
    return false;
  ask_ = static_cast<std::uint8_t>(channel + 1);
  return true;
}

int SerialPulseDriver::take_asked(double& at_s) {
  if (asked_ == 0) return -1;
  at_s = asked_at_s_;
  const int channel = asked_ - 1;
  asked_ = 0;
  return channel;
}

double SerialPulseDriver::waiting_until_s() const {
  return waiting_.valid ? wire_free_s_ - credit_s_ : std::numeric_limits<double>::infinity();
}

// The frame that waited, once the wire is free (for the session the last
// report named, which may be newer than when it was written).
void SerialPulseDriver::send_waiting() {
  if (!waiting_.valid || session_ == 0 || bus::monotonic_s() < wire_free_s_ - credit_s_) return;
  waiting_.valid = false;
  send_pulses(waiting_.pulse_us, waiting_.count, waiting_.armed);
}

bool SerialPulseDriver::command(std::uint8_t command, std::uint32_t channels, std::uint8_t repeat) {
  if (config_.protocol == MM_LINK_PROTOCOL_PWM || session_ == 0) return false;
  if (channels == 0 || (channels >> config_.count) != 0) return false;
  mm_link_command c{};
  c.session = session_;
  c.sequence = ++sequence_;
  c.command = command;
  c.channels = static_cast<std::uint8_t>(channels);
  c.repeat = repeat;
  std::uint8_t buf[MM_LINK_MAX_FRAME];
  const std::size_t n = mm_link_encode_command(&c, buf);
  return n > 0 && send(buf, n);
}

bool SerialPulseDriver::service(double now_s) {
  if (lost_) return false;
  std::uint8_t buf[256];
  for (;;) {
    const ssize_t n = ::read(fd_, buf, sizeof buf);
    if (n > 0) {
      for (ssize_t i = 0; i < n; ++i) {
        mm_link_frame f{};
        const std::uint8_t type = mm_link_feed(&parser_, buf[i], &f);
        if (type == MM_LINK_TELEMETRY) take_telemetry(f.u.telemetry);
        if (type == MM_LINK_REPORT) {
          report_ = f.u.report;
          ++reports_;
          // A new session (the chip started, or its link timed out): go on
          // from the last sequence it took.
          if (report_.session != session_) {
            session_ = report_.session;
            sequence_ = report_.last_sequence;
            ++sessions_;
          } else {
            sequence_ = std::max(sequence_, report_.last_sequence);
            // Far ahead of what the chip took (frames it refused piled up):
            // back to its last, or the chip would refuse every jump.
            if (sequence_ - report_.last_sequence > MM_LINK_MAX_SEQUENCE_STEP / 2)
              sequence_ = report_.last_sequence;
          }
          if (!(report_.flags & MM_LINK_FLAG_CONFIGURED)) resend_config_ = true;
        }
      }
      continue;
    }
    if (n == 0 || errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) break;
    if (errno == EIO) break;  // a pty whose other end is not open yet
    return false;
  }
  if (resend_config_ || now_s >= next_config_s_) {
    send_config();
    next_config_s_ = now_s + 1.0;
  }
  send_waiting();
  return !lost_;
}

// A reply's period is one electrical revolution in microseconds; its
// largest (511 << 7) is what an ESC sends for a stopped motor.
void SerialPulseDriver::take_telemetry(const mm_link_telemetry& t) {
  constexpr double kStoppedPeriodUs = 511.0 * 128.0;
  constexpr std::size_t kMaxWaiting = 64;  // readings nobody took: the oldest go
  for (int r = 0; r < t.readings; ++r) {
    ErpmReading reading;
    reading.erpm.resize(static_cast<std::size_t>(t.count));
    for (int c = 0; c < t.count; ++c) {
      const double period = t.period_us[r][c];
      double& erpm = reading.erpm[static_cast<std::size_t>(c)];
      if (period == MM_LINK_NO_REPLY) {
        erpm = std::numeric_limits<double>::quiet_NaN();
        ++replies_missed_;
      } else {
        erpm = period >= kStoppedPeriodUs ? 0.0 : 60e6 / period;
        ++replies_decoded_;
      }
    }
    if (erpm_.size() >= kMaxWaiting) erpm_.erase(erpm_.begin());
    erpm_.push_back(std::move(reading));
  }
}

std::vector<PulseDriver::ErpmReading> SerialPulseDriver::take_erpm() {
  std::vector<ErpmReading> out;
  out.swap(erpm_);
  return out;
}

std::optional<FirmwareReport> SerialPulseDriver::firmware_report() const {
  if (reports_ == 0) return std::nullopt;
  FirmwareReport r;
  r.frames = report_.frames;
  r.crc_errors = report_.crc_errors;
  r.malformed = report_.malformed;
  r.link_timeouts = report_.link_timeouts;
  r.watchdog_resets = report_.watchdog_resets;
  r.rejected = report_.rejected;
  r.flags = report_.flags;  // MM_LINK_FLAG_* are output_status_t's FIRMWARE_* bits
  return r;
}

std::string SerialPulseDriver::describe() const {
  std::ostringstream s;
  s << "serial: " << frames_sent_ << " frames sent, " << write_failures_ << " not written";
  if (held_ > 0) s << ", " << held_ << " held before the firmware's first report";
  if (superseded_ > 0)
    s << ", " << superseded_ << " replaced by a newer one while the wire was busy";
  if (reports_ == 0) {
    s << "; no report from the firmware yet (it reports every 50 ms; a firmware older than "
         "link version "
      << MM_LINK_VERSION << " is not understood: flash firmware/pulses)";
    return s.str();
  }
  if (report_.version != MM_LINK_VERSION) {
    s << "; the firmware speaks link version " << static_cast<int>(report_.version)
      << ", this motormix " << MM_LINK_VERSION
      << ": it refuses the configuration and makes no pulse (flash firmware/pulses)";
    return s.str();
  }
  s << "; firmware: " << report_.frames << " frames taken, " << report_.crc_errors
    << " CRC errors, " << report_.malformed << " malformed, " << report_.rejected << " refused, "
    << report_.link_timeouts << " link timeouts, " << report_.watchdog_resets
    << " watchdog resets, "
    << ((report_.flags & MM_LINK_FLAG_CONFIGURED) == 0  ? "unconfigured"
        : (report_.flags & MM_LINK_FLAG_ARMED) != 0     ? "armed pulses"
        : (report_.flags & MM_LINK_FLAG_TIMED_OUT) != 0 ? "disarmed (its link watchdog)"
                                                        : "disarmed pulses");
  return s.str();
}

}  // namespace motormix::output
