#pragma once
// ESCs answering bidirectional DShot on the simulated board's pins, as
// BLHeli_32, AM32 and Bluejay do: each decodes the chip's inverted frames
// as they happen (DshotEsc, inverted checksum) and, for every good one,
// pulls its line for a 21-bit eRPM reply at 5/4 of the frame's bitrate
// some 30 us after the frame: a start bit and four GCR codes of the period
// (3-bit exponent, 9-bit mantissa, microseconds per electrical revolution)
// and its inverted checksum, each 1 a change of level. What makes it a
// real wire rather than an ideal one: each ESC's clock off by a fixed share,
// every edge jittered, the reply's start varying, replies not sent at all,
// and spikes on some (all seeded).

#include "avr_board.hpp"
#include "dshot_esc.hpp"

#include <atomic>
#include <cstdint>
#include <random>
#include <vector>

namespace motormix::avr {

struct BidirEscNoise {
  double delay_us_min = 25.0, delay_us_max = 35.0;  // frame's last edge to the reply
  double clock_error_max = 0.01;                    // each ESC's clock, fixed, uniformly within +-
  double edge_jitter_cycles = 1.5;  // each edge, uniformly within +- (16 MHz cycles)
  double lost_share = 0.01;         // frames left unanswered
  double spike_share = 0.0;         // replies with a 2-4 cycle spike of the other level
  std::uint32_t seed = 1;
};

// The period an ESC sends for an eRPM: mantissa << exponent, the smallest
// exponent that fits the mantissa in 9 bits; 65408 (0xFFF) for a stopped
// motor (below 917 eRPM, slower than the largest period).
std::uint16_t erpm_period_us(double erpm);

class BidirEscs {
 public:
  // frame_bit_cycles: the frame's bit at 16 MHz (26.67 at DShot600).
  BidirEscs(AvrBoard& board, int count, double frame_bit_cycles, BidirEscNoise noise);
  void set_erpm(int channel, double erpm) { erpm_[static_cast<std::size_t>(channel)] = erpm; }
  // Motors that turn as they are told: each frame sets its channel's eRPM
  // to full_erpm times the throttle's share of 48..2047 (0 for a stop or a
  // command). 0: off (set_erpm's values stand).
  void follow_throttle(double full_erpm) { follow_erpm_ = full_erpm; }
  // A motor that stopped (a burnt winding, a locked rotor): 0 eRPM from its
  // next reply on, whatever it is told. Safe from another thread.
  void stop_motor(int channel) { stopped_.fetch_or(1u << channel); }

  struct Answer {
    DshotFrame frame;
    double erpm = 0.0;       // the motor's, when the frame came
    std::uint16_t sent = 0;  // the period sent; 0 when not answered
    bool spiked = false;
  };
  // Every frame each ESC decoded, in order (answered or not).
  const std::vector<Answer>& answers(int channel) const {
    return answers_[static_cast<std::size_t>(channel)];
  }
  int broken(int channel) const { return escs_[static_cast<std::size_t>(channel)].broken(); }

 private:
  void on_edge(const PinEdge& e);
  void reply(int channel, std::uint64_t after_cycle, std::uint16_t period_us);

  AvrBoard& board_;
  double reply_bit_cycles_;
  BidirEscNoise noise_;
  std::mt19937 rng_;
  std::vector<DshotEsc> escs_;
  std::vector<double> erpm_, clock_;
  std::vector<std::vector<Answer>> answers_;
  double follow_erpm_ = 0.0;
  std::atomic<unsigned> stopped_{0};
};

}  // namespace motormix::avr
