#pragma once
// What `motormix output` drives: the pulse firmware over a serial port or
// Linux hardware PWM. One call per decision, with every motor's pulse in
// microseconds (already the disarmed ones when not armed).

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace motormix::output {

// What the hardware behind the driver says of itself (the pulse firmware's
// report; output_status_t's firmware_* fields).
struct FirmwareReport {
  std::uint64_t frames = 0, crc_errors = 0, malformed = 0;
  std::uint32_t link_timeouts = 0, watchdog_resets = 0, rejected = 0;
  std::uint8_t flags = 0;  // output_status_t FIRMWARE_* bits
};

// Every channel armed (write's mask).
inline constexpr std::uint32_t kAllArmed = 0xFFFFFFFFU;

class PulseDriver {
 public:
  virtual ~PulseDriver() = default;
  // False when the hardware refused the values (counted by the caller).
  // armed: bit i set when pulse i is an armed value (the firmware clamps it
  // into the armed range), clear when it is the channel's disarmed pulse.
  virtual bool write(const double* pulse_us, int count, std::uint32_t armed) = 0;
  // Work between writes (reading the firmware's reports); false on a lost
  // device.
  virtual bool service(double now_s) {
    (void)now_s;
    return true;
  }
  // A DShot special command (1..47) on the channels of `channels` (bit i:
  // channel i), in `repeat` frames; the caller sends it only while every
  // output is disarmed. False when the hardware cannot (not DShot, not
  // written).
  // Bidirectional DShot: the eRPM each ESC answered with, one reading per
  // frame since the last call (oldest first), NaN where a reply was
  // missing or broken. Empty for other drivers.
  struct ErpmReading {
    std::vector<double> erpm;  // one per channel
  };
  virtual std::vector<ErpmReading> take_erpm() { return {}; }
  virtual bool command(std::uint8_t command, std::uint32_t channels, std::uint8_t repeat) {
    (void)command;
    (void)channels;
    (void)repeat;
    return false;
  }
  // KISS telemetry requests (DShot only: the telemetry bit in one frame of
  // the channel asked). ask_telemetry(c) puts channel c's request in the
  // next frame that goes (it waits while an earlier one has not gone; a
  // later call replaces it); false when the hardware cannot ask.
  // take_asked: the channel whose request went in a frame since the last
  // call and when (monotonic seconds), -1 if none went.
  virtual bool ask_telemetry(int channel) {
    (void)channel;
    return false;
  }
  virtual int take_asked(double& at_s) {
    (void)at_s;
    return -1;
  }
  // A driver paced to its wire keeps the newest frame while the wire is
  // busy: when that frame can go (monotonic seconds; infinity when none
  // waits), and sending it once that time has come (else nothing).
  virtual double waiting_until_s() const { return std::numeric_limits<double>::infinity(); }
  virtual void send_waiting() {}
  // The hardware's latest report, when it sends one.
  virtual std::optional<FirmwareReport> firmware_report() const { return std::nullopt; }
  // One line on the hardware's own state, for the log.
  virtual std::string describe() const = 0;
};

}  // namespace motormix::output
