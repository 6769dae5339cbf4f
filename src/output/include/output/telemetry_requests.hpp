#pragma once
// Which ESC is asked for its KISS telemetry next, and which request each
// reading answers. A KISS / BLHeli_32 ESC sends a 10-byte frame on its
// telemetry wire only after a DShot frame whose telemetry bit is set; the
// ESCs are asked in turn, one request per frame that goes (the pulse
// firmware sets the bit in that channel's next frame alone). A reading on a
// wire answers the request that went to its motor within answer_window_s
// before it: it was measured then, not when it arrived. A reading nobody
// asked for, and a request nothing answered, are counted.
//
// Pure: time is passed in (monotonic seconds); no I/O.

#include <motormix/config/hardware.hpp>

#include <cstdint>
#include <optional>
#include <vector>

namespace motormix::output {

// How long after its request a KISS reading may arrive: the ESC's 10-byte
// frame (0.87 ms at 115200 baud), a USB serial adapter's latency timer (up
// to 16 ms), the output's tick.
inline constexpr double kKissAnswerWindowS = 0.030;

// The motors (0-based) with a telemetry wire, in the configuration's order.
std::vector<int> wired_motors(const config::Hardware& hardware);

class TelemetryRequests {
 public:
  struct Counts {
    std::uint64_t asked = 0;       // requests that went
    std::uint64_t answered = 0;    // readings matched to their request
    std::uint64_t unasked = 0;     // readings with no request open for their motor
    std::uint64_t unanswered = 0;  // requests that saw no reading within the window
  };

  // wired: the channels (0-based motors) with a telemetry wire, asked in
  // this order; answer_window_s: how long after its request a reading may
  // arrive (the ESC's frame, the serial adapter's latency).
  TelemetryRequests(std::vector<int> wired, double answer_window_s);

  bool empty() const { return wired_.empty(); }
  // The channel to ask next (-1 when no wire).
  int next() const;
  // A request for `channel` went at at_s: the next one is the following wire.
  void asked(int channel, double at_s);
  // A reading arrived on `channel`'s wire at now_s: when its request went,
  // or nothing when no request for it is open (counted as unasked).
  std::optional<double> answered(int channel, double now_s);
  const Counts& counts() const { return counts_; }

 private:
  void expire(std::size_t slot, double now_s);
  std::vector<int> wired_;
  std::vector<double> open_since_s_;  // per wire: the open request's time; NaN none
  std::size_t next_ = 0;
  double window_s_;
  Counts counts_;
};

}  // namespace motormix::output
