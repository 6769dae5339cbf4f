#pragma once
// The pulse firmware (firmware/pulses) behind a serial port: nothing until
// the firmware's first report names its session (src/link), then a CONFIG
// frame, again whenever a report says the chip has none (it was reset) and
// once a second; one PULSES frame per write, for the session the last
// report named; the firmware's reports read back. A write that finds the device gone makes
// service() return false: the caller reopens it (a new driver).
//
// Paced to the wire: frames take at most kWireShare of it on average. Each
// frame sent owes its bytes' time on the wire over kWireShare (from the baud
// rate); a PULSES frame goes while what is owed is at most one frame's
// time, else it waits, the newest replacing one that waited, until then
// (waiting_until_s, send_waiting). That one frame of credit lets two values
// that a publisher's jitter brings close together go at once (with no
// credit, a 400 Hz stream's frames waited up to 1.7 ms whenever two came
// less than 1.7 ms apart), and two frames fit the chip's receive ring.
// Values faster than the share (a loop rate above some 580 Hz for four
// motors at 250000 baud) would otherwise queue in the kernel, tens of
// milliseconds of old thrust ahead of the newest, and leave the chip no time
// for its own work (with bidirectional DShot it then loses host frames). A
// frame that arms or disarms a channel never waits.

#include "output/pulse_driver.hpp"

#include "motormix_link.h"

#include <cstdint>
#include <vector>

namespace motormix::output {

struct SerialPulseSettings {
  double period_us = 2500.0;
  double link_timeout_ms = 100.0;
  double min_us = 1000.0;  // the firmware clamps armed pulses into [min_us, max_us] too
  double max_us = 2000.0;
  std::vector<double> disarmed_us;  // one per motor
  // MM_LINK_PROTOCOL_*: with DShot, period_us is the frame period and
  // min_us..max_us the throttle range (the firmware maps it onto 48..2047).
  std::uint8_t protocol = MM_LINK_PROTOCOL_PWM;
  // Bidirectional DShot (DShot300 or 600): every ESC's eRPM back, read from
  // the firmware's TELEMETRY frames by take_erpm().
  bool bidirectional = false;
  double baud = 250000.0;  // for the pacing: 10 bits a byte
};

// The most of the wire the driver's frames take (see above).
inline constexpr double kWireShare = 0.6;

class SerialPulseDriver : public PulseDriver {
 public:
  // Takes ownership of fd (an open, non-blocking serial port or pty).
  // Throws std::invalid_argument if the settings make no valid CONFIG.
  SerialPulseDriver(int fd, const SerialPulseSettings& settings);
  ~SerialPulseDriver() override;

  bool write(const double* pulse_us, int count, std::uint32_t armed) override;
  bool command(std::uint8_t command, std::uint32_t channels, std::uint8_t repeat) override;
  bool service(double now_s) override;
  std::string describe() const override;
  std::optional<FirmwareReport> firmware_report() const override;
  std::vector<ErpmReading> take_erpm() override;
  double waiting_until_s() const override;
  void send_waiting() override;
  bool ask_telemetry(int channel) override;
  int take_asked(double& at_s) override;
  // eRPM replies the firmware decoded, and those it found missing or broken.
  std::uint64_t replies_decoded() const { return replies_decoded_; }
  std::uint64_t replies_missed() const { return replies_missed_; }

  std::uint64_t reports() const { return reports_; }
  const mm_link_report& report() const { return report_; }
  std::uint64_t frames_sent() const { return frames_sent_; }
  // PULSES frames replaced by a newer one while they waited for the wire.
  std::uint64_t superseded() const { return superseded_; }
  std::uint64_t write_failures() const { return write_failures_; }
  std::uint32_t session() const { return session_; }
  // Sessions the firmware named (its start, then one per link timeout).
  std::uint64_t sessions() const { return sessions_; }

 private:
  bool send(const std::uint8_t* bytes, std::size_t n);
  void send_config();
  bool send_pulses(const double* pulse_us, int count, std::uint8_t armed);
  // KISS telemetry: the request for the next frame (channel + 1, 0 none),
  // and the one that went last with when (channel + 1, 0 none).
  std::uint8_t ask_ = 0, asked_ = 0;
  double asked_at_s_ = 0.0;

  int fd_;
  mm_link_config config_{};
  mm_link_parser parser_{};
  mm_link_report report_{};
  std::uint64_t reports_ = 0;
  std::uint32_t session_ = 0;   // the firmware's, from its reports; 0: none heard yet
  std::uint32_t sequence_ = 0;  // the last one sent in it
  std::uint64_t sessions_ = 0, held_ = 0;
  double next_config_s_ = 0.0;
  bool resend_config_ = true;
  std::uint64_t frames_sent_ = 0, write_failures_ = 0;
  bool lost_ = false;  // a write found the device gone: service() says so
  // Pacing: until when the wire's share is owed (monotonic seconds), one
  // PULSES frame's share of time (the credit), and the newest frame waiting.
  double byte_s_ = 10.0 / 250000.0;
  double wire_free_s_ = 0.0;
  double credit_s_ = 0.0;
  bool sent_pulses_ = false;
  std::uint8_t last_armed_ = 0;
  struct Waiting {
    bool valid = false;
    std::uint8_t armed = 0;
    int count = 0;
    double pulse_us[MM_LINK_MAX_CHANNELS] = {};
  } waiting_;
  std::uint64_t superseded_ = 0;
  void take_telemetry(const mm_link_telemetry& t);
  std::vector<ErpmReading> erpm_;
  std::uint64_t replies_decoded_ = 0, replies_missed_ = 0;
};

}  // namespace motormix::output
