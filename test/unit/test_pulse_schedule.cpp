// The pulse firmware's schedule (firmware/pulses/pulse_schedule.c, compiled
// here for the host): over 10^5 seeded random sets of up to eight widths,
// crowded and spread, every channel falls within one tick (0.5 us) of its
// width, at the edge that clears its pin; consecutive edges are at least
// MM_MIN_GAP_TICKS apart (what the interrupt's waiting loop can write) and
// marked polled exactly when closer than MM_POLL_GAP_TICKS, with a UART
// byte taken before those at least MM_TAKE_GAP_TICKS from the one before.

#include "pulse_schedule.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <random>

namespace motormix::test {
namespace {

constexpr int kScheduleCases = 100000;
constexpr int kMaxErrorTicks = 1;
constexpr int kMaxBlindTicks = (MM_LINK_MAX_CHANNELS - 1) * static_cast<int>(MM_TAKE_GAP_TICKS);

TEST(PulseSchedule, EveryChannelFallsWithinATickAndEdgesKeepTheirGap) {
  std::mt19937 rng(3737);
  for (int c = 0; c < kScheduleCases; ++c) {
    const auto count = static_cast<std::uint8_t>(1 + rng() % MM_LINK_MAX_CHANNELS);
    const int spread = c % 3 == 0 ? 2000 : c % 3 == 1 ? 20 : 6;  // ticks
    const int base = 2000 + static_cast<int>(rng() % 1900);
    std::uint16_t w[MM_LINK_MAX_CHANNELS];
    for (int i = 0; i < count; ++i) w[i] = static_cast<std::uint16_t>(base + rng() % spread);
    mm_schedule s{};
    mm_schedule_build(w, count, &s);
    ASSERT_GE(s.n, 1);
    std::uint8_t rise_d = 0, rise_b = 0;
    mm_rise_ports(count, &rise_d, &rise_b);
    for (int i = 0; i < count; ++i) {
      std::uint8_t bd = 0, bb = 0;
      mm_channel_bits(static_cast<std::uint8_t>(i), &bd, &bb);
      // The edge that clears this channel's bit: the first whose ports lack it.
      int k = 0;
      while (k < s.n && ((s.fall[k].port_d & bd) != 0 || (s.fall[k].port_b & bb) != 0)) ++k;
      ASSERT_LT(k, s.n) << "channel " << i << " never falls";
      EXPECT_LE(std::abs(static_cast<int>(s.fall[k].at) - static_cast<int>(w[i])), kMaxErrorTicks)
          << "case " << c << " channel " << i;
    }
    for (int k = 1; k < s.n; ++k) {
      const int gap = s.fall[k].at - s.fall[k - 1].at;
      EXPECT_GE(gap, static_cast<int>(MM_MIN_GAP_TICKS)) << "case " << c;
      EXPECT_EQ(s.fall[k].polled, gap < static_cast<int>(MM_POLL_GAP_TICKS) ? 1 : 0);
      EXPECT_EQ(s.fall[k].take_uart,
                s.fall[k].polled && gap >= static_cast<int>(MM_TAKE_GAP_TICKS) ? 1 : 0);
    }
    // Inside the interrupt, the UART waits unread only across polled edges
    // without a take: at most seven gaps shorter than MM_TAKE_GAP_TICKS.
    int blind = 0;
    for (int k = 1; k < s.n; ++k) {
      blind =
          s.fall[k].polled && !s.fall[k].take_uart ? blind + (s.fall[k].at - s.fall[k - 1].at) : 0;
      EXPECT_LT(blind, kMaxBlindTicks) << "case " << c;
    }
    EXPECT_EQ(s.fall[0].polled, 0);
    EXPECT_EQ(s.fall[s.n - 1].port_d, 0);  // every pin low after the last edge
    EXPECT_EQ(s.fall[s.n - 1].port_b, 0);
  }
}

}  // namespace
}  // namespace motormix::test
