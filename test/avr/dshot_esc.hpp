#pragma once
// An ESC's DShot input, emulated from the pin edges simavr records: it
// splits a channel's edges into frames, measures every bit (period, high
// time) and decodes it as the ESC firmwares do (AM32 and Bluejay: a bit is
// 1 when its high time is longer than half a bit), then checks the frame's
// checksum. The tests hold what it measured against the protocol's numbers
// (docs/wiring-it-to-motors.md, "DShot").

#include "avr_board.hpp"

#include <cstdint>
#include <vector>

namespace motormix::avr {

struct DshotFrame {
  std::uint64_t start_cycle;  // the first bit's rise
  std::uint16_t value;        // 11 bits: 0 stop, 1..47 commands, 48..2047 throttle
  bool telemetry;             // the telemetry request bit
  bool crc_ok;
  // Measured, in cycles of the 16 MHz chip.
  double bit_min, bit_max;              // rise to rise, bits 1..15
  double bit_mean;                      // first rise to 16th over 15
  double zero_high_min, zero_high_max;  // high time of the 0 bits (0 if none)
  double one_high_min, one_high_max;    // of the 1 bits (0 if none)
};

class DshotEsc {
 public:
  // nominal_bit_cycles: the protocol's bit (26.67 at DShot600 at 16 MHz):
  // a gap of more than 3 bits starts a new frame. inverted: bidirectional
  // DShot (the line idles high, a bit is low for its "high" time, and the
  // checksum is inverted).
  DshotEsc(int channel, double nominal_bit_cycles, bool inverted = false);
  // One edge as it happens (edges an ESC drove itself are skipped).
  void feed(const PinEdge& e);
  // Takes the edges of every channel since the last call; frames complete
  // once their 16th bit has fallen.
  void feed(const std::vector<PinEdge>& edges);
  std::vector<DshotFrame> take_frames();
  // Rises that made no 16-bit frame (a frame cut short, noise).
  int broken() const { return broken_; }

 private:
  void finish();

  int channel_;
  double nominal_;
  bool inverted_;
  std::vector<std::uint64_t> rises_, falls_;
  std::vector<DshotFrame> frames_;
  bool high_ = false;
  int broken_ = 0;
};

}  // namespace motormix::avr
