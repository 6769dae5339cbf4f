// The firmware's reception at the real ATmega328P's receive depth (two bytes
// and one in the shift register, AvrBoard::kReceiveDepth): for every
// protocol the chip takes, the traffic patterns `motormix output` produces
// (frames back to back in pairs, one every period, bursts of four when the
// armed channels change) at the wire's full rate. Every frame is taken, no
// byte is lost, and the longest a byte waits unread is printed per protocol
// (docs/hardware/firmware.md). The Host's destructor fails a test on any
// overrun.

#include "avr_board.hpp"
#include "firmware_host.hpp"
#include "motormix_link.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <random>
#include <vector>

namespace motormix::avr {
namespace {

struct Case {
  const char* name;
  std::uint8_t protocol;
  std::uint8_t channels;
  std::uint16_t period_us;
  double spread_us;  // widths within this of each other: close falls chain in the interrupt
};
constexpr Case kCases[] = {
    {"PWM 400 Hz, 4 channels", MM_LINK_PROTOCOL_PWM, 4, 2500, 1000.0},
    {"PWM 400 Hz, 8 channels within 100 us", MM_LINK_PROTOCOL_PWM, 8, 2500, 100.0},
    {"DShot150 1 kHz", MM_LINK_PROTOCOL_DSHOT150, 4, 1000, 1000.0},
    {"DShot300 1 kHz", MM_LINK_PROTOCOL_DSHOT300, 4, 1000, 1000.0},
    {"DShot600 1 kHz", MM_LINK_PROTOCOL_DSHOT600, 4, 1000, 1000.0},
    {"bidirectional DShot600 1 kHz",
     static_cast<std::uint8_t>(MM_LINK_PROTOCOL_DSHOT600 | MM_LINK_PROTOCOL_BIDIRECTIONAL), 4, 1000,
     1000.0},
};
constexpr int kFramesPerPattern = 400;
constexpr double kOutputWireShare = 0.6;  // SerialPulseDriver's kWireShare
constexpr double kLongestUnreadBoundUs = kLongestUnreadUs;

TEST(ReceiveDepth, EveryFrameTakenAtTheRealDepthForEveryProtocolAndPattern) {
  for (const Case& c : kCases) {
    Host h;
    h.send_config(h.config(c.channels, c.period_us, 1000, c.protocol));
    h.board.run_for_us(20000);
    const std::uint32_t frames_before = h.last_report().frames;
    std::mt19937 rng(2027);
    std::uniform_real_distribution<double> base(1000.0, 2000.0 - c.spread_us);
    std::uniform_real_distribution<double> within(0.0, c.spread_us);
    auto widths = [&] {
      std::vector<double> w(c.channels);
      const double b = base(rng);
      for (double& x : w) x = b + within(rng);
      return w;
    };
    // The output's pacing (SerialPulseDriver): frames take at most this
    // share of the wire on average; each frame's bytes go back to back.
    const double frame_us = 40.0 * static_cast<double>(h.pulses_frame(widths(), true).size());
    const double share_us = frame_us / kOutputWireShare;
    int sent = 0;
    // Pairs back to back (the output's frame of credit spent), then one
    // frame a period, then bursts of four (what the output sends at once
    // when the armed channels change: it does not pace those), each no
    // faster than the output's share of the wire.
    for (int k = 0; k < kFramesPerPattern / 2; ++k) {
      h.send_pulses(widths());
      h.send_pulses(widths());
      sent += 2;
      h.board.run_for_us(std::max(2.0 * c.period_us, 2.0 * share_us));
    }
    for (int k = 0; k < kFramesPerPattern; ++k) {
      h.send_pulses(widths());
      ++sent;
      h.board.run_for_us(std::max(static_cast<double>(c.period_us), share_us));
    }
    for (int k = 0; k < kFramesPerPattern / 4; ++k) {
      h.send_pulses(widths());
      h.send_pulses(widths(), false);
      h.send_pulses(widths());
      h.send_pulses(widths());
      sent += 4;
      h.board.run_for_us(std::max(8.0 * c.period_us, 8.0 * share_us));
    }
    h.board.run_for_us(60000);
    const mm_link_report r = h.last_report();
    std::printf(
        "%s: %d frames sent, %u taken, %u CRC errors, %u malformed; longest unread %.1f us, "
        "overruns %d\n",
        c.name, sent, r.frames - frames_before, r.crc_errors, r.malformed,
        h.board.longest_unread_us(), h.board.overruns());
    EXPECT_EQ(r.frames - frames_before, static_cast<std::uint32_t>(sent)) << c.name;
    EXPECT_EQ(r.crc_errors + r.malformed + r.rejected, 0u) << c.name;
    EXPECT_EQ(h.board.overruns(), 0) << c.name;
    EXPECT_LT(h.board.longest_unread_us(), kLongestUnreadBoundUs) << c.name;
  }
}

}  // namespace
}  // namespace motormix::avr
