// Bidirectional DShot in the firmware (firmware/pulses/dshot_reply.c),
// against emulated ESCs that answer every frame with their eRPM
// (bidir_esc.hpp): edges jittered by up to 3 cycles (0.19 us), ESC clocks
// off by up to 2 %, replies starting 20-40 us after the frame, 1 % of
// frames left unanswered, and spikes on 0.5 % of the replies. The chip samples port D once for all
// four motors, decodes each reply and sends the periods to the host in TELEMETRY frames; here they
// are matched, frame by frame, with what each ESC sent.

#include "avr_board.hpp"
#include "bidir_esc.hpp"
#include "firmware_host.hpp"
#include "motormix_link.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <vector>

namespace motormix::avr {
namespace {

constexpr int kChannels = 4;
// The fastest the chip takes with replies (MM_LINK_MIN_BIDIR_PERIOD_US):
// 1 kHz.
constexpr std::uint16_t kFramePeriodUs = MM_LINK_MIN_BIDIR_PERIOD_US;
// The bounds: replies decoded per motor (with noise), eRPM against
// the ESC's.
constexpr double kMinDecodedShare = 0.995;
constexpr double kErpmTolerance = 0.01;
// What the 9-bit mantissa leaves at worst (a period of 256 us or more).
constexpr double kErpmQuantisation = 1.0 / 256.0;

struct Speed {
  std::uint8_t protocol;
  double rate;
  const char* name;
};

struct Tally {
  std::size_t answered = 0, decoded = 0, missed = 0, wrong = 0, unanswered_reported = 0;
  std::size_t spiked = 0, spiked_decoded = 0, spiked_wrong = 0, undelivered = 0;
  double worst_erpm_error = 0.0;
};

// The eRPM of each motor over the run: ramps and a stop, so every exponent
// from 0 to 7 is sent (a period of 120 us to a stopped motor).
double erpm_at(int channel, int ms) {
  if (channel == 3 && ms > 1200) return 0.0;  // a motor that stops
  const double base[kChannels] = {30000.0, 120000.0, 7000.0, 60000.0};
  return base[channel] * (1.0 + 0.5 * std::sin(ms * 0.004 + channel));
}

// The host's frames: at 400 Hz, as `motormix run` publishes by default; as
// often as `motormix output` sends them at most (its pacing: a frame's
// bytes take at most kOutputWireShare of the wire); or back to back,
// filling the wire (a host other than motormix's output, a loop rate above
// what 250000 baud carries).
enum class HostTraffic { k400Hz, kOutputsMost, kSaturated };
constexpr double kOutputWireShare = 0.6;  // SerialPulseDriver's
// Under a full wire: the share of the host's frames the chip takes at
// least (the rest lost in its receive ring, counted), so that the newest
// command reaches the pins every few milliseconds.
constexpr double kMinTakenSaturated = 0.10;

void run_speed(const Speed& speed, const BidirEscNoise& noise, std::vector<Tally>& tally,
               double& frame_rate_hz, HostTraffic traffic = HostTraffic::k400Hz) {
  Host h;
  const double bit_cycles = 16e6 / speed.rate;
  BidirEscs escs(h.board, kChannels, bit_cycles, noise);
  mm_link_config c =
      h.config(kChannels, kFramePeriodUs, 1000,
               static_cast<std::uint8_t>(speed.protocol | MM_LINK_PROTOCOL_BIDIRECTIONAL));
  h.send_config(c);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> width(1100.0, 1900.0);
  const auto send_random = [&] {
    std::vector<double> w(kChannels);
    for (double& x : w) x = width(rng);
    h.send_pulses(w);
  };
  const double frame_us = (7.0 + MM_LINK_PULSES_BODY(kChannels)) * 10.0 / 250000.0 * 1e6;
  double next_send_us = h.board.now_us();
  constexpr int kMs = 2000;
  int sent_frames = 0;
  for (int ms = 0; ms < kMs; ++ms) {
    for (int ch = 0; ch < kChannels; ++ch) escs.set_erpm(ch, erpm_at(ch, ms));
    const double ms_end_us = h.board.now_us() + 1000.0;
    if (traffic == HostTraffic::kOutputsMost) {
      // The output's worst: its one frame of credit spent at every turn,
      // two frames back to back every two shares of time.
      while (next_send_us < ms_end_us) {
        h.board.run_for_us(std::max(0.0, next_send_us - h.board.now_us()));
        send_random();
        send_random();
        sent_frames += 2;
        next_send_us += 2.0 * frame_us / kOutputWireShare;
      }
    } else if (traffic == HostTraffic::kSaturated) {
      // Always a frame waiting behind the one on the wire.
      while (h.board.queued() < 2 * MM_LINK_PULSES_BODY(kChannels)) {
        send_random();
        ++sent_frames;
      }
    } else if (ms % 5 == 2) {  // PULSES at 200 Hz, alternating with 400 Hz
      send_random();
      ++sent_frames;
    } else if (ms % 5 == 4) {
      std::vector<double> w(kChannels, 1500.0);
      h.send_pulses(w);
      ++sent_frames;
    }
    h.board.run_for_us(std::max(0.0, ms_end_us - h.board.now_us()));
    h.last_report();
  }
  h.board.run_for_us(60000);
  const mm_link_report r = h.last_report();
  std::printf(
      "%s: report: frames %u, crc errors %u, malformed %u, rejected %u, watchdog resets %u, "
      "link timeouts %u; %d reports, %zu telemetry frames; %d frames sent\n",
      speed.name, r.frames, r.crc_errors, r.malformed, r.rejected, r.watchdog_resets,
      r.link_timeouts, h.reports, h.telemetry.size(), sent_frames);
  if (traffic == HostTraffic::kSaturated) {
    EXPECT_GE(r.frames, kMinTakenSaturated * sent_frames) << speed.name;
  } else {
    EXPECT_EQ(r.frames, static_cast<std::uint32_t>(sent_frames)) << speed.name;
    EXPECT_EQ(r.crc_errors + r.malformed, 0u) << speed.name;
  }
  EXPECT_EQ(r.rejected, 0u) << speed.name;
  EXPECT_EQ(h.board.drive_conflicts(), 0) << speed.name << ": an ESC drove a line the chip drove";
  EXPECT_EQ(r.watchdog_resets + r.link_timeouts, 0u) << speed.name;

  // The chip's readings by frame number (0: the first frame after the
  // configuration, as the ESCs count them).
  std::map<std::uint32_t, std::vector<std::uint16_t>> readings;
  for (const mm_link_telemetry& t : h.telemetry) {
    ASSERT_EQ(t.count, kChannels);
    for (int i = 0; i < t.readings; ++i) {
      std::vector<std::uint16_t> v(t.period_us[i], t.period_us[i] + kChannels);
      readings[static_cast<std::uint16_t>(t.first + i)] = v;
    }
  }
  for (int ch = 0; ch < kChannels; ++ch) {
    EXPECT_EQ(escs.broken(ch), 0) << speed.name;
    const auto& answers = escs.answers(ch);
    ASSERT_GT(answers.size(), 1500u) << speed.name;
    Tally& t = tally[static_cast<std::size_t>(ch)];
    for (std::size_t i = 0; i + 5 < answers.size(); ++i) {  // the last few may still be on the wire
      const auto& a = answers[i];
      EXPECT_TRUE(a.frame.crc_ok) << speed.name;
      const auto it = readings.find(static_cast<std::uint32_t>(i & 0xFFFFu));
      if (it == readings.end()) {
        ++t.undelivered;
        continue;
      }
      const std::uint16_t got = it->second[static_cast<std::size_t>(ch)];
      if (a.sent == 0) {
        t.unanswered_reported += got == MM_LINK_NO_REPLY ? 0 : 1;
        continue;
      }
      if (a.spiked) {
        ++t.spiked;
        t.spiked_decoded += got == a.sent ? 1 : 0;
        t.spiked_wrong += got != a.sent && got != MM_LINK_NO_REPLY ? 1 : 0;
        continue;
      }
      ++t.answered;
      if (got == MM_LINK_NO_REPLY) {
        ++t.missed;
      } else if (got != a.sent) {
        ++t.wrong;
      } else {
        ++t.decoded;
        if (a.erpm > 1000.0) {
          const double erpm = 60e6 / got;
          t.worst_erpm_error = std::max(t.worst_erpm_error, std::abs(erpm - a.erpm) / a.erpm);
        }
      }
    }
  }
  const auto& a0 = escs.answers(0);
  // How regular the frames are: the loop sends one late when it was busy
  // (a burst of bytes, the replies), and the next early.
  double longest_us = 0.0;
  for (std::size_t i = 1; i < a0.size(); ++i)
    longest_us =
        std::max(longest_us,
                 static_cast<double>(a0[i].frame.start_cycle - a0[i - 1].frame.start_cycle) / 16.0);
  std::printf("%s: longest gap between frames %.0f us (period %u us)\n", speed.name, longest_us,
              kFramePeriodUs);
  frame_rate_hz =
      static_cast<double>(a0.size() - 1) /
      (static_cast<double>(a0.back().frame.start_cycle - a0.front().frame.start_cycle) / 16e6);
}

void report_and_check(const Speed& speed, const std::vector<Tally>& tally, double rate_hz,
                      bool spikes) {
  for (int ch = 0; ch < kChannels; ++ch) {
    const Tally& t = tally[static_cast<std::size_t>(ch)];
    const double share =
        t.answered > 0 ? static_cast<double>(t.decoded) / static_cast<double>(t.answered) : 0.0;
    std::printf(
        "%s motor %d: %zu replies, %zu decoded (%.2f %%), %zu missed, %zu wrong; worst eRPM error "
        "%.3f %%; unanswered frames reported: %zu; spiked %zu: %zu decoded, %zu wrong; readings "
        "not delivered %zu; %.1f frames/s\n",
        speed.name, ch + 1, t.answered, t.decoded, 100.0 * share, t.missed, t.wrong,
        100.0 * t.worst_erpm_error, t.unanswered_reported, t.spiked, t.spiked_decoded,
        t.spiked_wrong, t.undelivered, rate_hz);
    EXPECT_GE(share, kMinDecodedShare) << speed.name << " motor " << ch + 1;
    EXPECT_EQ(t.wrong, 0u) << speed.name;
    EXPECT_EQ(t.unanswered_reported, 0u) << speed.name;
    EXPECT_EQ(t.undelivered, 0u) << speed.name;
    EXPECT_LE(t.worst_erpm_error, kErpmQuantisation) << speed.name;
    EXPECT_LE(t.worst_erpm_error, kErpmTolerance) << speed.name;
    if (spikes) {
      EXPECT_GT(t.spiked, 0u);
    }
  }
  EXPECT_GE(rate_hz, 1e6 / kFramePeriodUs * (1.0 - 1e-3)) << speed.name;
}

constexpr Speed kSpeeds[] = {{MM_LINK_PROTOCOL_DSHOT600, 600e3, "DShot600"},
                             {MM_LINK_PROTOCOL_DSHOT300, 300e3, "DShot300"}};

// Four motors at 1 kHz, each speed, with the noise above: >= 99.5 % of the
// replies decoded per motor, never a wrong period, eRPM within the
// mantissa's resolution of the ESC's, every reading delivered to the host
// while it keeps sending PULSES frames (none lost, no UART overrun).
TEST(PulseFirmwareBidir, EveryMotorsReplyDecodedOnTheChipWithNoise) {
  for (const Speed& speed : kSpeeds) {
    BidirEscNoise noise;
    noise.seed = 11;
    noise.spike_share = 0.005;
    // Twice the defaults' jitter and clock error, and a wider delay.
    noise.edge_jitter_cycles = 3.0;
    noise.clock_error_max = 0.02;
    noise.delay_us_min = 20.0;
    noise.delay_us_max = 40.0;
    std::vector<Tally> tally(kChannels);
    double rate = 0.0;
    run_speed(speed, noise, tally, rate);
    report_and_check(speed, tally, rate, true);
  }
}

// The host's frames as often as `motormix output` sends them at most (some
// 580 a second with four motors, in pairs: its one frame of credit): every
// one taken, every reply decoded.
// Back to back (some 930 a second, the wire full, as a host other than
// motormix's output might): the chip still sends its frames at the rate
// configured, decodes and delivers every motor's replies, never resets nor
// times out, and takes at least kMinTakenSaturated of the host's frames
// (the rest lost in its receive ring, counted). Before 0.10, a full wire
// left the main loop no turn for the replies: no frame went, and the
// hardware watchdog reset the chip within 60 ms.
TEST(PulseFirmwareBidir, TheOutputsMostFramesAllTakenAndAFullWireNeverStopsTheFrames) {
  for (const HostTraffic traffic : {HostTraffic::kOutputsMost, HostTraffic::kSaturated}) {
    for (const Speed& speed : kSpeeds) {
      BidirEscNoise noise;
      noise.seed = 23;
      std::vector<Tally> tally(kChannels);
      double rate = 0.0;
      run_speed(speed, noise, tally, rate, traffic);
      report_and_check(speed, tally, rate, false);
    }
  }
}

}  // namespace
}  // namespace motormix::avr
