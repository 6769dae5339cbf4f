// The pulse firmware (firmware/pulses) as built for the ATmega328P, run in
// simavr: pulse widths measured on the emulated pins against what the frames
// asked for, the link watchdog, the hardware watchdog, the sequence and
// configuration rules, and a stream of corrupted frames that must never
// change a pulse. Nothing here depends on the host's speed: time is the
// simulated chip's cycle counter.

#include "avr_board.hpp"
#include "dshot_esc.hpp"
#include "firmware_host.hpp"
#include "motormix_link.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <map>
#include <random>
#include <string>
#include <vector>

#ifndef MOTORMIX_FIRMWARE_ELF
#error "MOTORMIX_FIRMWARE_ELF: the firmware under test"
#endif

namespace motormix::avr {
namespace {

// What the firmware reaches for a width in whole half microseconds with no
// other channel within 2 us of it (an edge's timing is fixed to a cycle
// or two: 0.0625 us each).
constexpr double kExactToleranceUs = 0.2;
// Closer channels fall together or 1.5 us apart: at most half a microsecond
// off, and a width sent in half microseconds is rounded by a quarter.
constexpr double kGroupedToleranceUs = 0.5 + 0.25 + kExactToleranceUs;
constexpr double kPeriodUs = 2500.0;  // 400 Hz
constexpr double kUsPerCycle = 1.0 / 16.0;

TEST(PulseFirmware, NoPulseBeforeAConfigurationThenDisarmedPulses) {
  Host h;
  h.board.run_for_us(30000);
  EXPECT_TRUE(h.board.take_edges().empty()) << "pulses before any configuration";
  h.send_config(h.config(4, 2500, 1000));
  h.board.run_for_us(30000);
  const std::vector<Pulse> pulses = h.board.take_pulses();
  ASSERT_GE(pulses.size(), 4u * 10u);
  for (const Pulse& p : pulses) EXPECT_NEAR(p.width_us, 1000.0, kExactToleranceUs);
  // 400 Hz: consecutive rises of channel 0 one period apart, to within what
  // entering an interrupt varies by: the instruction in progress finishes
  // first (up to 4 cycles, a call or a return), which the main loop's code
  // decides, not the firmware's timing.
  constexpr double kRiseJitterUs = 4.0 * kUsPerCycle;
  std::vector<std::uint64_t> rises;
  for (const Pulse& p : pulses)
    if (p.channel == 0) rises.push_back(p.rise_cycle);
  for (std::size_t i = 1; i < rises.size(); ++i)
    EXPECT_NEAR(static_cast<double>(rises[i] - rises[i - 1]) * kUsPerCycle, kPeriodUs,
                kRiseJitterUs);
  const mm_link_report r = h.last_report();
  EXPECT_TRUE(r.flags & MM_LINK_FLAG_CONFIGURED);
  EXPECT_FALSE(r.flags & MM_LINK_FLAG_ARMED);
  EXPECT_FALSE(h.board.pin_high(4)) << "a channel past the configured count pulsed";
}

// Random widths and the cases that stress the interrupt: equal widths,
// 1, 2 and 3 us apart, a chain of 2 us steps, edges just under and over the
// interrupt's re-entry gap.
TEST(PulseFirmware, ArmedPulsesAreTheWidthsAskedForWithinOneMicrosecond) {
  Host h;
  h.send_config(h.config());
  h.board.run_for_us(10000);
  std::vector<std::vector<double>> sets = {
      {1000, 1234, 1500, 1987},     {1500, 1500, 1500, 1500},     {1400, 1401, 1402, 1403},
      {1400, 1402, 1404, 1406},     {1400, 1403, 1406, 1409},     {1400, 1415, 1416, 1431},
      {1400, 1417, 1434, 1451},     {2000, 1999, 1001, 1000},     {1000, 1000, 2000, 2000},
      {1400, 1400.5, 1401, 1401.5}, {1500, 1500.5, 1501.5, 1502}, {1300.25, 1300.75, 1301.1, 1302}};
  // Random widths with any fraction (as motor_pwm_t carries them), half of
  // the sets crowded within 10 us, as four motors in a hover are.
  std::mt19937 rng(37);
  std::uniform_real_distribution<double> width(1000.0, 2000.0), near(0.0, 10.0);
  for (int k = 0; k < 400; ++k) {
    const double base = width(rng);
    std::vector<double> s(4);
    for (auto& w : s) w = k % 2 ? width(rng) : std::min(2000.0, base + near(rng));
    sets.push_back(s);
  }
  double worst = 0.0, worst_exact = 0.0;
  for (const auto& s : sets) {
    h.send_pulses(s);
    h.board.run_for_us(2 * kPeriodUs);  // the frame's bytes and one period after them
    h.board.take_pulses();
    h.board.run_for_us(kPeriodUs);
    const auto got = Host::last_widths(h.board.take_pulses());
    ASSERT_EQ(got.size(), 4u);
    for (int ch = 0; ch < 4; ++ch) {
      // Alone: no other channel within 2 us (closer ones are grouped, and a
      // group can move the next one by a tick).
      bool alone = true;
      for (int other = 0; other < 4; ++other)
        alone &= other == ch || std::abs(s[other] - s[ch]) >= 2.0 || s[other] == s[ch];
      const bool whole_half = std::abs(2.0 * s[ch] - std::round(2.0 * s[ch])) < 1e-9;
      const double err = std::abs(got.at(ch) - s[ch]);
      worst = std::max(worst, err);
      if (alone && whole_half) worst_exact = std::max(worst_exact, err);
      EXPECT_LE(err, kGroupedToleranceUs) << "channel " << ch << " asked " << s[ch];
      EXPECT_LE(err, kPulseToleranceUs);
    }
  }
  EXPECT_LE(worst_exact, kExactToleranceUs);
  std::printf(
      "pulse error: worst %.3f us; %.3f us for widths in whole half microseconds with no "
      "other channel within 2 us (%zu sets)\n",
      worst, worst_exact, sets.size());
  h.board.run_for_us(60000);  // a report after the last frame
  const mm_link_report r = h.last_report();
  EXPECT_EQ(r.frames, sets.size());
  EXPECT_EQ(r.crc_errors + r.malformed + r.rejected, 0u);
  EXPECT_TRUE(r.flags & MM_LINK_FLAG_ARMED);
}

// Frames at the pulse rate, each completing at the same point of the period
// (the host's 400 Hz against the chip's: their phase drifts slowly, so a
// frame that lands where the pulse interrupt starts a period keeps landing
// there for tens of milliseconds). Every frame must be in the pulses of the
// first period that starts after it was taken, at every phase. Measured
// before the fix: frames completing in the last 0.3 ms before a rise were
// held back as long as the phase held (the interrupt kept the old schedule
// while the main loop was writing the next one, and the main loop wrote the
// next frame into the same buffer again).
TEST(PulseFirmware, FramesInStepWithThePeriodAreTakenAtTheNextRise) {
  // From a frame's last byte to its schedule being ready: the parse of the
  // queued bytes and the schedule's build (measured: 0.275-0.3 ms).
  constexpr double kTakeBoundUs = 400.0;
  constexpr std::uint64_t kCyclesPerUs = 16;
  constexpr std::uint64_t kByteCycles = 640;  // 10 bits at 250000 baud
  constexpr int kFramesPerPhase = 6;
  constexpr int kPhases = 100;
  const auto period = static_cast<std::uint64_t>(kPeriodUs) * kCyclesPerUs;
  Host h;
  h.send_config(h.config());
  h.send_pulses({1500, 1500, 1500, 1500});
  h.board.run_for_us(20000);
  // A rise of channel 0: the periods are where this one says.
  std::uint64_t rise = 0;
  for (const PinEdge& e : h.board.take_edges())
    if (e.channel == 0 && e.high) rise = e.cycle;
  ASSERT_GT(rise, 0u);
  h.board.take_pulses();
  struct Sent {
    std::uint64_t done;  // the cycle its last byte is in
    double width;
  };
  std::vector<Sent> sent;
  int value = 0;
  for (int phase = 0; phase < kPhases; ++phase) {
    const std::uint64_t offset = period * static_cast<std::uint64_t>(phase) / kPhases;
    for (int k = 0; k < kFramesPerPhase; ++k) {
      const double w = 1100.0 + (value++ % 800);
      const std::vector<std::uint8_t> frame = h.pulses_frame({w, w, w, w}, true);
      // The next period boundary plus the phase, far enough ahead for the
      // frame's bytes.
      std::uint64_t done = rise + offset;
      while (done < h.board.cycle() + frame.size() * kByteCycles + period) done += period;
      h.board.run_until(done - frame.size() * kByteCycles);
      h.board.send(frame);
      sent.push_back({done, w});
    }
  }
  h.board.run_for_us(3 * kPeriodUs);
  const std::vector<Pulse> pulses = h.board.take_pulses();
  // Each period of channel 0 after the first frame: its pulse is a frame
  // that had come in before the rise, and none older than the newest frame
  // taken by then (in by kTakeBound before the rise).
  int late = 0, periods = 0;
  const auto bound = static_cast<std::uint64_t>(kTakeBoundUs) * kCyclesPerUs;
  for (const Pulse& p : pulses) {
    if (p.channel != 0 || p.rise_cycle < sent.front().done + bound) continue;
    ++periods;
    std::size_t must = 0, may = 0;  // one past the last frame taken / in
    while (must < sent.size() && sent[must].done + bound <= p.rise_cycle) ++must;
    while (may < sent.size() && sent[may].done <= p.rise_cycle) ++may;
    bool ok = false;
    for (std::size_t i = must - 1; i < may; ++i)
      ok |= std::abs(p.width_us - sent[i].width) <= kPulseToleranceUs;
    if (!ok && ++late <= 5)
      std::printf("period %.1f us after frame %zu came in: %.1f us, that frame asked %.1f\n",
                  static_cast<double>(p.rise_cycle - sent[must - 1].done) / kCyclesPerUs, must - 1,
                  p.width_us, sent[must - 1].width);
  }
  std::printf("%zu frames at %d phases of the period, %d periods: %d held an older frame\n",
              sent.size(), kPhases, periods, late);
  EXPECT_EQ(late, 0);
  h.board.run_for_us(60000);
  const mm_link_report r = h.last_report();
  EXPECT_EQ(r.crc_errors + r.malformed + r.rejected, 0u);
}

// One channel armed (a motor test through motormix output): its width,
// clamped into [min, max]; every other channel its disarmed pulse, not the
// armed minimum.
TEST(PulseFirmware, OneArmedChannelAloneIsAMotorTest) {
  Host h;
  mm_link_config c = h.config(4, 2500, 950);
  h.send_config(c);
  h.board.run_for_us(10000);
  const std::vector<double> widths = {1700, 1120, 1800, 1900};
  for (int i = 0; i < 6; ++i) {
    std::vector<std::uint8_t> f = h.pulses_frame(widths, true);
    // The armed byte (after sync, length, type, session, sequence): channel 1 alone.
    f[3 + 9] = 0x2;
    const std::uint32_t crc = mm_link_crc32(0, f.data() + 2, f.size() - 6);
    for (int b = 0; b < 4; ++b) f[f.size() - 4 + b] = static_cast<std::uint8_t>(crc >> (8 * b));
    h.board.send(f);
    h.board.run_for_us(kPeriodUs);
  }
  h.board.take_pulses();
  h.board.run_for_us(2 * kPeriodUs);
  const std::map<int, double> w = Host::last_widths(h.board.take_pulses());
  EXPECT_NEAR(w.at(0), 950.0, kExactToleranceUs);
  EXPECT_NEAR(w.at(1), 1120.0, kExactToleranceUs);
  EXPECT_NEAR(w.at(2), 950.0, kExactToleranceUs);
  EXPECT_NEAR(w.at(3), 950.0, kExactToleranceUs);
  h.board.run_for_us(60000);
  EXPECT_TRUE(h.last_report().flags & MM_LINK_FLAG_ARMED);  // a configuration would be refused
}

TEST(PulseFirmware, EightChannelsAtFiftyHertz) {
  Host h;
  h.send_config(h.config(8, 20000, 1000));
  h.board.run_for_us(25000);
  const std::vector<double> s = {1100, 1200, 1300, 1400, 1500, 1600, 1700, 1800};
  h.send_pulses(s);
  h.board.run_for_us(45000);
  h.board.take_pulses();
  h.board.run_for_us(20000);
  const auto got = Host::last_widths(h.board.take_pulses());
  ASSERT_EQ(got.size(), 8u);
  for (int ch = 0; ch < 8; ++ch) EXPECT_NEAR(got.at(ch), s[ch], kExactToleranceUs) << ch;
}

TEST(PulseFirmware, LinkWatchdogDisarmsWithinTheTimeoutOfTheLastFrame) {
  Host h;
  h.send_config(h.config());
  h.board.run_for_us(10000);
  const std::vector<double> armed = {1600, 1650, 1700, 1750};
  for (int i = 0; i < 40; ++i) {
    h.send_pulses(armed);
    h.board.run_for_us(kPeriodUs);
  }
  while (h.board.sending()) h.board.run_for_us(10);
  const std::uint64_t last_frame = h.board.cycle();  // its last byte is in
  h.board.take_pulses();
  h.board.run_for_us(150000);
  std::uint64_t first_disarmed = 0;
  for (const Pulse& p : h.board.take_pulses()) {
    if (std::abs(p.width_us - 1000.0) < kExactToleranceUs) {
      first_disarmed = p.rise_cycle;
      break;
    }
    EXPECT_GT(p.width_us, 1599.0) << "a pulse neither armed nor disarmed";
  }
  ASSERT_NE(first_disarmed, 0u) << "no disarmed pulse after the link went quiet";
  const double after_ms = static_cast<double>(first_disarmed - last_frame) * kUsPerCycle / 1000.0;
  std::printf("first disarmed pulse %.2f ms after the last frame (timeout %.0f ms)\n", after_ms,
              kLinkTimeoutMs);
  EXPECT_LE(after_ms, kLinkTimeoutMs);
  EXPECT_GE(after_ms, kLinkTimeoutMs - 2 * kPeriodUs / 1000.0) << "disarmed too early";
  const mm_link_report r = h.last_report();
  EXPECT_EQ(r.link_timeouts, 1u);
  EXPECT_TRUE(r.flags & MM_LINK_FLAG_TIMED_OUT);
  EXPECT_FALSE(r.flags & MM_LINK_FLAG_ARMED);
  // A new session: frames for the old one, newer or not, are refused...
  const std::uint32_t old_session = h.session;
  EXPECT_NE(r.session, old_session);
  const std::uint16_t refused = r.rejected;
  h.seq += 1000;
  h.send_pulses(armed);
  h.board.run_for_us(3 * kPeriodUs);
  h.board.take_pulses();
  h.board.run_for_us(kPeriodUs);
  EXPECT_NEAR(Host::last_widths(h.board.take_pulses()).at(3), 1000.0, kExactToleranceUs);
  h.board.run_for_us(60000);
  EXPECT_EQ(h.last_report().rejected, refused + 1);
  // ...and the link is back from the next frame for the new one.
  h.learn_session();
  EXPECT_EQ(h.session, r.session);
  h.send_pulses(armed);
  h.board.run_for_us(3 * kPeriodUs);
  h.board.take_pulses();
  h.board.run_for_us(kPeriodUs);
  EXPECT_NEAR(Host::last_widths(h.board.take_pulses()).at(3), 1750.0, kExactToleranceUs);
}

// The failsafe at the limits of what the chip accepts: the longest period
// with the shortest timeout it allows (two periods), the shortest period
// that fits a 2000 us pulse with the shortest timeout, and the shortest
// timeout at exactly two periods. Outputs disarm within the timeout of the last
// frame plus one period; a timeout shorter than two periods (whose count,
// timeout less a period, once wrapped to 8.4 s) is refused as malformed.
TEST(PulseFirmware, TheFailsafeHoldsAtTheLimitsOfEveryAcceptedConfiguration) {
  struct Limit {
    std::uint16_t period_us, timeout_ms;
  };
  for (const Limit l : {Limit{25000, 50}, Limit{2040, 10}, Limit{5000, 10}}) {
    SCOPED_TRACE("period " + std::to_string(l.period_us) + " us, timeout " +
                 std::to_string(l.timeout_ms) + " ms");
    Host h;
    mm_link_config c = h.config(4, l.period_us);
    c.link_timeout_ms = l.timeout_ms;
    h.send_config(c);
    h.board.run_for_us(4.0 * l.period_us);
    const std::vector<double> armed = {1600, 1650, 1700, 1750};
    for (int i = 0; i < 6; ++i) {
      h.send_pulses(armed);
      h.board.run_for_us(l.period_us);
    }
    while (h.board.sending()) h.board.run_for_us(10);
    const std::uint64_t last_frame = h.board.cycle();
    h.board.take_pulses();
    h.board.run_for_us(l.timeout_ms * 1000.0 + 3.0 * l.period_us);
    std::uint64_t first_disarmed = 0;
    for (const Pulse& p : h.board.take_pulses()) {
      if (std::abs(p.width_us - 1000.0) < kExactToleranceUs) {
        first_disarmed = p.rise_cycle;
        break;
      }
    }
    ASSERT_NE(first_disarmed, 0u) << "still armed after the timeout and a period";
    const double after_ms = static_cast<double>(first_disarmed - last_frame) * kUsPerCycle / 1000.0;
    EXPECT_LE(after_ms, l.timeout_ms + l.period_us / 1000.0);
  }
  // One period short of the rule: refused, no pulse at all.
  Host h;
  mm_link_config c = h.config(4, 25000);
  c.link_timeout_ms = 49;
  std::uint8_t buf[MM_LINK_MAX_FRAME];
  EXPECT_EQ(mm_link_encode_config(&c, buf), 0u) << "the host's encoder refuses it too";
  c.link_timeout_ms = 50;
  c.session = h.session;
  c.sequence = h.seq++;
  const std::size_t n = mm_link_encode_config(&c, buf);
  ASSERT_GT(n, 0u);
  buf[3 + 11] = 49;  // the timeout's low byte, after the encoder's check
  const std::uint32_t crc = mm_link_crc32(0, buf + 2, n - 6);
  for (int b = 0; b < 4; ++b) buf[n - 4 + b] = static_cast<std::uint8_t>(crc >> (8 * b));
  h.board.send(buf, n);
  h.board.run_for_us(100000);
  EXPECT_TRUE(h.board.take_pulses().empty());
  EXPECT_EQ(h.last_report().malformed, 1u);
}

// A frame whose sequence is far beyond the last one taken (a host whose
// counter started wrong) is refused and counted; it locks nothing out: the
// next frames in sequence are taken at once.
TEST(PulseFirmware, AWildSequenceIsRefusedAndLocksNoSessionOut) {
  Host h;
  h.send_config(h.config());
  h.board.run_for_us(10000);
  h.send_pulses({1500, 1500, 1500, 1500});
  h.board.run_for_us(3 * kPeriodUs);
  const std::uint32_t good = h.seq;
  h.seq += 0x80000000U;  // half the counter away
  h.send_pulses({1900, 1900, 1900, 1900});
  h.board.run_for_us(3 * kPeriodUs);
  h.seq = good + static_cast<std::uint32_t>(MM_LINK_MAX_SEQUENCE_STEP) + 1;  // one beyond
  h.send_pulses({1900, 1900, 1900, 1900});
  h.board.run_for_us(3 * kPeriodUs);
  h.board.take_pulses();
  h.board.run_for_us(kPeriodUs);
  EXPECT_NEAR(Host::last_widths(h.board.take_pulses()).at(0), 1500.0, kExactToleranceUs);
  h.seq = good + 5;  // frames lost on the way: a small step is taken
  h.send_pulses({1700, 1700, 1700, 1700});
  h.board.run_for_us(3 * kPeriodUs);
  h.board.take_pulses();
  h.board.run_for_us(kPeriodUs);
  EXPECT_NEAR(Host::last_widths(h.board.take_pulses()).at(0), 1700.0, kExactToleranceUs);
  h.board.run_for_us(60000);
  const mm_link_report r = h.last_report();
  EXPECT_EQ(r.rejected, 2u);
  EXPECT_EQ(r.link_timeouts, 0u);
}

// Frames recorded before a link timeout (issue 49: an independent probe
// played frames 1.5-2 s old into the chip between good ones, and 92 pulses
// followed them under the 8-bit sequence). MOTORMIX_AVR_REPLAYED_FRAMES
// recorded frames (10^5 by default; fewer under the sanitizers), from a
// session that timed out, armed with other widths and with sequence numbers
// far above the current ones, and recorded configurations, go in between
// good frames: not one pulse may follow them.
TEST(PulseFirmwareReplay, FramesFromBeforeALinkTimeoutMoveNoPulse) {
  const char* env = std::getenv("MOTORMIX_AVR_REPLAYED_FRAMES");
  const int frames = env ? std::atoi(env) : 100000;
  Host h;
  h.send_config(h.config());
  h.board.run_for_us(10000);
  // The recording: a second of armed frames, sequences climbing high (far
  // above what the next session will use, within one step of the last).
  std::mt19937 rng(20261205);
  std::vector<std::vector<std::uint8_t>> recorded;
  h.seq += static_cast<std::uint32_t>(MM_LINK_MAX_SEQUENCE_STEP) - 500;
  for (int i = 0; i < 400; ++i) {
    std::vector<double> w(4);
    for (auto& x : w) x = static_cast<double>(1000 + rng() % 1001);
    recorded.push_back(h.pulses_frame(w, true));
    h.board.send(recorded.back());
    h.board.run_for_us(kPeriodUs);
  }
  mm_link_config other = h.config(4, 2500, 1100);
  h.send_pulses({1500, 1500, 1500, 1500}, false);
  h.board.run_for_us(3 * kPeriodUs);
  {
    mm_link_config copy = other;
    copy.session = h.session;
    copy.sequence = h.seq + (1u << 20);
    std::vector<std::uint8_t> buf(MM_LINK_MAX_FRAME);
    buf.resize(mm_link_encode_config(&copy, buf.data()));
    recorded.push_back(buf);  // a configuration, recorded and never sent
  }
  // The link times out; the host comes back in the new session.
  h.board.run_for_us(150000);
  h.learn_session();
  const std::vector<double> widths = {1200, 1400, 1600, 1800};
  h.send_pulses(widths);
  h.board.run_for_us(3 * kPeriodUs);
  h.board.take_pulses();
  int changed = 0, pulses = 0;
  for (int k = 0; k < frames; ++k) {
    h.board.send(recorded[rng() % recorded.size()]);
    if (k % 4 == 3) h.send_pulses(widths);
    changed += h.drain_and_count_changed(widths, pulses, "replayed", k);
  }
  h.board.run_for_us(60000);
  const mm_link_report r = h.last_report();
  std::printf(
      "%d replayed frames from before a link timeout: %d pulses measured, %d changed; "
      "%u refused, %u link timeouts\n",
      frames, pulses, changed, r.rejected, r.link_timeouts);
  EXPECT_EQ(changed, 0);
  EXPECT_GT(pulses, frames / 4);
  // Every replayed frame refused and counted (the report's counter is 16
  // bits wide: it wraps).
  EXPECT_EQ(r.rejected, static_cast<std::uint16_t>(frames));
  EXPECT_EQ(r.link_timeouts, 1u);
}

TEST(PulseFirmware, OldFramesAndConfigurationsWhileArmedAreRefusedAndCounted) {
  Host h;
  h.send_config(h.config());
  h.board.run_for_us(10000);
  h.send_pulses({1500, 1500, 1500, 1500});
  const std::vector<std::uint8_t> replayed = h.pulses_frame({1900, 1900, 1900, 1900}, true);
  h.send_pulses({1500, 1500, 1500, 1500});
  h.board.run_for_us(3 * kPeriodUs);
  h.board.send(replayed);  // a valid frame, one sequence number old
  h.send_config(h.config(4, 2500, 1100));
  h.board.run_for_us(4 * kPeriodUs);
  h.board.take_pulses();
  h.send_pulses({1500, 1500, 1500, 1500});
  h.board.run_for_us(3 * kPeriodUs);
  for (const Pulse& p : h.board.take_pulses()) EXPECT_NEAR(p.width_us, 1500.0, kExactToleranceUs);
  h.board.run_for_us(60000);
  mm_link_report r = h.last_report();
  EXPECT_EQ(r.rejected, 2u);  // the old frame and the configuration while armed
  // Disarmed, the new configuration is taken.
  h.send_pulses({1500, 1500, 1500, 1500}, false);
  h.board.run_for_us(3 * kPeriodUs);
  h.send_config(h.config(4, 2500, 1100));
  h.board.run_for_us(4 * kPeriodUs);
  h.board.take_pulses();
  h.board.run_for_us(3 * kPeriodUs);
  for (const Pulse& p : h.board.take_pulses()) EXPECT_NEAR(p.width_us, 1100.0, kExactToleranceUs);
  // An armed frame and, right behind it, another configuration: whether or
  // not a period has started from the frame yet, the configuration is
  // refused.
  const std::uint16_t refused_before = h.last_report().rejected;
  h.send_pulses({1600, 1600, 1600, 1600});
  h.send_config(h.config(4, 2500, 1200));
  h.board.run_for_us(4 * kPeriodUs);
  h.board.take_pulses();
  h.send_pulses({1600, 1600, 1600, 1600});
  h.board.run_for_us(3 * kPeriodUs);
  for (const Pulse& p : h.board.take_pulses()) EXPECT_NEAR(p.width_us, 1600.0, kExactToleranceUs);
  h.board.run_for_us(60000);
  EXPECT_EQ(h.last_report().rejected, refused_before + 1);
}

TEST(PulseFirmware, HardwareWatchdogResetsAStuckChipToNoPulses) {
  Host h;
  h.send_config(h.config());
  h.board.run_for_us(10000);
  for (int i = 0; i < 10; ++i) {
    h.send_pulses({1700, 1700, 1700, 1700});
    h.board.run_for_us(kPeriodUs);
  }
  h.board.take_edges();
  const std::uint64_t stuck = h.board.cycle();
  h.board.disable_interrupts();  // the pulse interrupt stops; the main loop runs on
  h.board.run_for_us(100000);
  // No edge after the watchdog's 60 ms (+ its oscillator's tolerance), and
  // every pin low.
  for (const PinEdge& e : h.board.take_edges()) {
    const double ms = static_cast<double>(e.cycle - stuck) * kUsPerCycle / 1000.0;
    EXPECT_TRUE(ms < 80.0 && !e.high) << "edge " << ms << " ms after the chip got stuck";
  }
  for (int ch = 0; ch < 4; ++ch) EXPECT_FALSE(h.board.pin_high(ch));
  // It came back as from power-up: no pulse until configured, in a new
  // session (nothing sent before the reset is taken); the reset counted.
  const std::uint32_t before_reset = h.session;
  h.board.run_for_us(30000);
  EXPECT_TRUE(h.board.take_edges().empty());
  h.learn_session();
  EXPECT_GT(h.session, before_reset);
  h.send_config(h.config());
  h.board.run_for_us(60000);
  EXPECT_FALSE(h.board.take_pulses().empty());
  const mm_link_report r = h.last_report();
  EXPECT_EQ(r.watchdog_resets, 1u);
  EXPECT_TRUE(r.flags & MM_LINK_FLAG_CONFIGURED);
}

// MOTORMIX_AVR_CORRUPT_FRAMES corrupted frames (10^5 by default; fewer under
// the sanitizers), each of them bit flips, a truncation, a wrong CRC, random
// bytes behind a sync, or a valid frame replayed; a good frame with the same
// widths after every fourth keeps the link up. Not one pulse may change.
TEST(PulseFirmwareCorruption, CorruptedFramesNeverChangeAPulseAndAreCounted) {
  const char* env = std::getenv("MOTORMIX_AVR_CORRUPT_FRAMES");
  const int frames = env ? std::atoi(env) : 100000;
  Host h;
  h.send_config(h.config());
  h.board.run_for_us(10000);
  const std::vector<double> widths = {1300, 1450, 1451, 1800};
  h.send_pulses(widths);
  h.board.run_for_us(3 * kPeriodUs);
  h.board.take_pulses();
  std::mt19937 rng(20261204);
  int changed = 0, pulses = 0, sent_bad_crc_or_shape = 0, replays = 0;
  std::vector<std::uint8_t> old = h.pulses_frame(widths, true);
  for (int k = 0; k < frames; ++k) {
    std::vector<double> other(4);
    for (auto& w : other) w = static_cast<double>(1000 + rng() % 1001);
    std::vector<std::uint8_t> f = h.pulses_frame(other, true);
    const std::vector<std::uint8_t> intact = f;
    --h.seq;  // the corrupted frame's number is not used up
    switch (k % 5) {
      case 0:
        // Flips that cancel out leave a valid frame: flip until it differs.
        do {
          for (int b = 0, n = 1 + static_cast<int>(rng() % 8); b < n; ++b)
            f[rng() % f.size()] ^= static_cast<std::uint8_t>(1u << (rng() % 8));
        } while (f == intact);
        ++sent_bad_crc_or_shape;
        break;
      case 1:
        // Cut short; every frame after it starts with the sync 0xA5, so a
        // cut before a 0xA5 would be completed, intact, by the next one.
        do {
          f.assign(intact.begin(), intact.begin() + 1 + rng() % (intact.size() - 1));
        } while (intact[f.size()] == MM_LINK_SYNC0);
        break;
      case 2:
        f[f.size() - 1 - rng() % 4] ^= static_cast<std::uint8_t>(1 + rng() % 255);
        ++sent_bad_crc_or_shape;
        break;
      case 3:
        for (std::size_t i = 2; i < f.size(); ++i) f[i] = static_cast<std::uint8_t>(rng());
        break;
      default:
        f = old;  // captured earlier, valid, out of sequence
        ++replays;
        break;
    }
    h.board.send(f);
    if (k % 4 == 3) {
      old = h.pulses_frame(widths, true);
      h.board.send(old);
    }
    changed += h.drain_and_count_changed(widths, pulses, "corrupted", k);
  }
  h.board.run_for_us(60000);
  const mm_link_report r = h.last_report();
  std::printf(
      "%d corrupted frames: %d pulses measured, %d changed; firmware counted %u CRC "
      "errors, %u malformed, %u rejected, %u good frames; simavr's receiver full %d times\n",
      frames, pulses, changed, r.crc_errors, r.malformed, r.rejected, r.frames, h.board.xoffs());
  EXPECT_EQ(changed, 0);
  EXPECT_GT(pulses, frames / 2);
  EXPECT_EQ(r.link_timeouts, 0u);
  EXPECT_GE(r.crc_errors + r.malformed, static_cast<std::uint32_t>(sent_bad_crc_or_shape * 9 / 10));
  EXPECT_GE(r.rejected, static_cast<std::uint32_t>(replays));
}

// ---- DShot (CONFIG's protocol) against the emulated ESC (dshot_esc.hpp) ----

constexpr double kCyclesPerUsDshot = 16.0;
// The protocol's bit: 1/rate. The mean bit of a frame within 0.5 % of it
// (issue 65); each bit within one cycle of it, the finest a 16 MHz chip
// can make (no whole count of cycles is within 0.5 % of 26.67 or 53.33).
constexpr double kMeanBitToleranceShare = 0.005;
constexpr double kBitToleranceCycles = 1.0;
// High times as shares of the bit: nominal 0.375 (a 0) and 0.75 (a 1); an
// ESC decides at half a bit (AM32, Bluejay). Held to within 0.05 of a bit
// of that threshold at worst, and to 0.075 of nominal.
constexpr double kZeroHighMin = 0.30, kZeroHighMax = 0.45;
constexpr double kOneHighMin = 0.675, kOneHighMax = 0.825;

struct DshotSpeed {
  std::uint8_t protocol;
  double rate_bits_per_s;
  const char* name;
};
constexpr DshotSpeed kDshotSpeeds[] = {{MM_LINK_PROTOCOL_DSHOT600, 600e3, "DShot600"},
                                       {MM_LINK_PROTOCOL_DSHOT300, 300e3, "DShot300"},
                                       {MM_LINK_PROTOCOL_DSHOT150, 150e3, "DShot150"}};

// What the firmware sends for a width with min 1000 and max 2000 us (the
// link carries it in half microseconds).
std::uint16_t throttle_for(double width_us) {
  const double t =
      std::clamp(static_cast<double>(std::lround(2.0 * width_us)) / 2.0, 1000.0, 2000.0);
  return static_cast<std::uint16_t>(48 + std::lround((t - 1000.0) / 1000.0 * 1999.0));
}

// Every channel's emulated ESC fed from the board's edges.
struct Escs {
  Escs(int count, double bit_cycles) {
    for (int ch = 0; ch < count; ++ch) escs.emplace_back(ch, bit_cycles);
  }
  void feed(AvrBoard& board) {
    const std::vector<PinEdge> edges = board.take_edges();
    for (DshotEsc& e : escs) e.feed(edges);
  }
  std::vector<DshotEsc> escs;
};

// Four channels at 1 kHz, each speed: every frame decodes with a good
// checksum, bits and high times within the protocol's bounds, the frame
// rate as configured, and each frame's throttle the width asked for.
TEST(PulseFirmwareDshot, FourChannelsEveryFrameDecodedWithinTheProtocolsTimes) {
  constexpr int kChannels = 4;
  constexpr std::uint16_t kFramePeriodUs = 1000;  // 1 kHz
  constexpr int kSets = 60;
  for (const DshotSpeed& speed : kDshotSpeeds) {
    Host h;
    const double bit_cycles = kCyclesPerUsDshot * 1e6 / speed.rate_bits_per_s;
    Escs esc(kChannels, bit_cycles);
    h.send_config(h.config(kChannels, kFramePeriodUs, 1000, speed.protocol));
    h.board.run_for_us(5000);
    esc.feed(h.board);
    for (DshotEsc& e : esc.escs) {
      const auto stopped = e.take_frames();
      ASSERT_FALSE(stopped.empty()) << speed.name << ": motor stop frames after the configuration";
      for (const DshotFrame& f : stopped) EXPECT_EQ(f.value, 0) << speed.name;
    }
    std::mt19937 rng(41);
    std::uniform_real_distribution<double> width(1000.0, 2000.0);
    double mean_lo = 1e9, mean_hi = 0;
    double bit_lo = 1e9, bit_hi = 0, zero_lo = 1e9, zero_hi = 0, one_lo = 1e9, one_hi = 0;
    std::size_t frames = 0, bad = 0, wrong = 0;
    std::uint64_t first = 0, last = 0;
    for (int k = 0; k < kSets; ++k) {
      std::vector<double> w(kChannels);
      for (double& x : w) x = width(rng);
      if (k == 0) w = {1000.0, 2000.0, 1500.0, 1000.5};
      h.send_pulses(w);
      h.board.run_for_us(2000);  // the frame's bytes (0.9 ms) and a frame after
      esc.feed(h.board);
      h.board.run_for_us(8000);
      esc.feed(h.board);
      for (int ch = 0; ch < kChannels; ++ch) {
        const auto got = esc.escs[static_cast<std::size_t>(ch)].take_frames();
        for (std::size_t i = 0; i < got.size(); ++i) {
          const DshotFrame& f = got[i];
          ++frames;
          bad += f.crc_ok ? 0 : 1;
          bit_lo = std::min(bit_lo, f.bit_min);
          bit_hi = std::max(bit_hi, f.bit_max);
          mean_lo = std::min(mean_lo, f.bit_mean);
          mean_hi = std::max(mean_hi, f.bit_mean);
          if (f.zero_high_min > 0) {
            zero_lo = std::min(zero_lo, f.zero_high_min);
            zero_hi = std::max(zero_hi, f.zero_high_max);
          }
          if (f.one_high_min > 0) {
            one_lo = std::min(one_lo, f.one_high_min);
            one_hi = std::max(one_hi, f.one_high_max);
          }
          if (ch == 0) {
            if (first == 0) first = f.start_cycle;
            last = f.start_cycle;
          }
        }
        // The last frames (8 ms after the PULSES frame): the throttle asked.
        ASSERT_FALSE(got.empty());
        if (got.back().value != throttle_for(w[static_cast<std::size_t>(ch)]) ||
            got.back().telemetry) {
          ++wrong;
          std::printf("%s channel %d: %d for %.1f us\n", speed.name, ch, got.back().value,
                      w[static_cast<std::size_t>(ch)]);
        }
      }
    }
    for (const DshotEsc& e : esc.escs) EXPECT_EQ(e.broken(), 0) << speed.name;
    const double per_ch = static_cast<double>(frames) / kChannels;
    const double rate_hz = (per_ch - 1.0) / (static_cast<double>(last - first) / 16e6);
    std::printf(
        "%s, 4 channels: %zu frames, %zu bad checksums, %zu wrong throttles; %.1f frames/s per "
        "channel; bit %.4f-%.4f us, a frame's mean %.4f-%.4f us (nominal %.4f); high of a 0 "
        "%.4f-%.4f us, of a 1 %.4f-%.4f us\n",
        speed.name, frames, bad, wrong, rate_hz, bit_lo / 16.0, bit_hi / 16.0, mean_lo / 16.0,
        mean_hi / 16.0, 1e6 / speed.rate_bits_per_s, zero_lo / 16.0, zero_hi / 16.0, one_lo / 16.0,
        one_hi / 16.0);
    EXPECT_EQ(bad, 0u) << speed.name;
    EXPECT_EQ(wrong, 0u) << speed.name;
    EXPECT_GE(rate_hz, 1000.0 * (1.0 - 1e-3)) << speed.name;
    EXPECT_GE(bit_lo, bit_cycles - kBitToleranceCycles) << speed.name;
    EXPECT_LE(bit_hi, bit_cycles + kBitToleranceCycles) << speed.name;
    EXPECT_GE(mean_lo, bit_cycles * (1.0 - kMeanBitToleranceShare)) << speed.name;
    EXPECT_LE(mean_hi, bit_cycles * (1.0 + kMeanBitToleranceShare)) << speed.name;
    EXPECT_GE(zero_lo, kZeroHighMin * bit_cycles) << speed.name;
    EXPECT_LE(zero_hi, kZeroHighMax * bit_cycles) << speed.name;
    EXPECT_GE(one_lo, kOneHighMin * bit_cycles) << speed.name;
    EXPECT_LE(one_hi, kOneHighMax * bit_cycles) << speed.name;
    h.board.run_for_us(60000);
    const mm_link_report r = h.last_report();
    EXPECT_EQ(r.crc_errors + r.malformed + r.rejected, 0u) << speed.name;
    EXPECT_EQ(r.version, MM_LINK_VERSION);
  }
}

// A configuration that changes only the protocol (or only the
// bidirectional bit) is a different configuration: taken while disarmed.
TEST(PulseFirmwareDshot, AConfigurationChangingOnlyTheProtocolIsTakenWhileDisarmed) {
  constexpr int kChannels = 4;
  Host h;
  Escs esc(kChannels, 16.0 * 1e6 / 600e3);
  mm_link_config c = h.config(kChannels, 2500, 1000, MM_LINK_PROTOCOL_PWM);
  h.send_config(c);
  h.board.run_for_us(10000);
  ASSERT_FALSE(h.board.take_pulses().empty()) << "servo pulses first";
  c.protocol = MM_LINK_PROTOCOL_DSHOT600;
  h.send_config(c);
  h.board.run_for_us(2000);
  esc.feed(h.board);
  for (DshotEsc& e : esc.escs) e.take_frames();
  h.board.run_for_us(20000);
  esc.feed(h.board);
  for (int ch = 0; ch < kChannels; ++ch) {
    const auto frames = esc.escs[static_cast<std::size_t>(ch)].take_frames();
    EXPECT_GE(frames.size(), 6u) << "channel " << ch << ": no DShot after the protocol changed";
    for (const DshotFrame& f : frames) EXPECT_TRUE(f.crc_ok && f.value == 0);
  }
  c.protocol = MM_LINK_PROTOCOL_DSHOT600 | MM_LINK_PROTOCOL_BIDIRECTIONAL;
  c.period_us = 2500;
  h.send_config(c);
  h.board.run_for_us(60000);
  const mm_link_report r = h.last_report();
  EXPECT_EQ(r.rejected + r.malformed, 0u);
  EXPECT_TRUE(r.flags & MM_LINK_FLAG_CONFIGURED);
  // Inverted frames now: the line idles high.
  h.board.run_for_us(5000);
  h.board.take_edges();
  EXPECT_TRUE(h.board.pin_high(0)) << "bidirectional frames idle high";
}

// KISS telemetry is asked for in the PULSES frame (link version 5): the
// telemetry bit goes in the asked channel's next DShot frame alone, once,
// armed or disarmed, and in no other frame. Frames at 1 kHz, PULSES at
// 400 Hz asking each channel in turn, as `motormix output` does; an ESC
// answers only a frame with the bit (KISS), so one bit per request is one
// answer per request.
TEST(PulseFirmwareDshot, ATelemetryRequestSetsTheBitInOneFrameOfTheAskedChannel) {
  constexpr int kChannels = 4;
  constexpr int kRequests = 80;
  Host h;
  Escs esc(kChannels, 16.0 * 1e6 / 600e3);
  h.send_config(h.config(kChannels, 1000, 1000, MM_LINK_PROTOCOL_DSHOT600));
  h.board.run_for_us(5000);
  std::array<int, kChannels> asked{}, bits{}, wrong_value{};
  for (int k = 0; k < kRequests; ++k) {
    const bool armed = k >= kRequests / 4;  // disarmed (motor stop) at first
    const int ask = k % kChannels;
    ++asked[static_cast<std::size_t>(ask)];
    h.send_pulses({1200, 1400, 1600, 1800}, armed, ask);
    h.board.run_for_us(2500);
    esc.feed(h.board);
    for (int ch = 0; ch < kChannels; ++ch) {
      for (const DshotFrame& f : esc.escs[static_cast<std::size_t>(ch)].take_frames()) {
        EXPECT_TRUE(f.crc_ok);
        if (!f.telemetry) continue;
        ++bits[static_cast<std::size_t>(ch)];
        EXPECT_EQ(ch, ask) << "request " << k << ": the bit on another channel";
        // The bit rides on the frame the channel carries anyway.
        const std::uint16_t expected = armed ? throttle_for(1200.0 + 200.0 * ch) : 0;
        if (f.value != expected) ++wrong_value[static_cast<std::size_t>(ch)];
      }
    }
  }
  for (int ch = 0; ch < kChannels; ++ch) {
    EXPECT_EQ(bits[static_cast<std::size_t>(ch)], asked[static_cast<std::size_t>(ch)])
        << "channel " << ch << ": one bit per request";
    EXPECT_EQ(wrong_value[static_cast<std::size_t>(ch)], 0) << "channel " << ch;
  }
  // Without requests, no frame carries the bit.
  h.send_pulses({1200, 1400, 1600, 1800}, true);
  h.board.run_for_us(20000);
  esc.feed(h.board);
  for (DshotEsc& e : esc.escs)
    for (const DshotFrame& f : e.take_frames()) EXPECT_FALSE(f.telemetry);
  EXPECT_EQ(h.last_report().malformed, 0u);
}

// Disarmed channels and the link failsafe send motor stop (0): a channel
// the frame leaves disarmed, all of them once the frames stop (within the
// link timeout). (DShot frames come from the main loop, which feeds the
// hardware watchdog as a pulse period does: a stuck loop sends no frame and
// resets the chip to no signal at all.)
TEST(PulseFirmwareDshot, DisarmedAndTheLinkTimeoutSendMotorStop) {
  constexpr int kChannels = 4;
  Host h;
  Escs esc(kChannels, 16.0 * 1e6 / 600e3);
  h.send_config(h.config(kChannels, 1000, 1000, MM_LINK_PROTOCOL_DSHOT600));
  h.board.run_for_us(3000);
  mm_link_pulses p{};
  p.session = h.session;
  p.count = kChannels;
  p.armed = 0b0101;                                               // channels 0 and 2 armed
  for (int ch = 0; ch < kChannels; ++ch) p.pulse_hus[ch] = 3000;  // 1500 us
  // A few frames 10 ms apart, then silence.
  std::uint64_t last_frame_done = 0;
  for (int k = 0; k < 5; ++k) {
    p.sequence = h.seq++;
    std::uint8_t buf[MM_LINK_MAX_FRAME];
    h.board.send(buf, mm_link_encode_pulses(&p, buf));
    while (h.board.sending()) h.board.run_for_us(50);
    last_frame_done = h.board.cycle();
    h.board.run_for_us(10000);
  }
  esc.feed(h.board);
  for (int ch = 0; ch < kChannels; ++ch) {
    const auto got = esc.escs[static_cast<std::size_t>(ch)].take_frames();
    ASSERT_FALSE(got.empty());
    EXPECT_EQ(got.back().value, (ch % 2 == 0) ? throttle_for(1500.0) : 0) << "channel " << ch;
  }
  h.board.run_for_us(200000);
  esc.feed(h.board);
  double stop_after_ms = 1e9;
  for (int ch = 0; ch < kChannels; ++ch) {
    const auto got = esc.escs[static_cast<std::size_t>(ch)].take_frames();
    ASSERT_FALSE(got.empty());
    EXPECT_EQ(got.back().value, 0) << "channel " << ch;
    if (ch == 0) {
      for (const DshotFrame& f : got) {
        if (f.value == 0) {
          stop_after_ms = static_cast<double>(f.start_cycle - last_frame_done) / 16000.0;
          break;
        }
      }
    }
  }
  std::printf("DShot600: motor stop %.2f ms after the last frame (link timeout %.0f ms)\n",
              stop_after_ms, kLinkTimeoutMs);
  EXPECT_LE(stop_after_ms, kLinkTimeoutMs);
  EXPECT_GE(stop_after_ms, kLinkTimeoutMs - 2 * 1.0 - 1.0);  // held until then
  const mm_link_report r = h.last_report();
  EXPECT_EQ(r.link_timeouts, 1u);
}

// Special commands: sent only while every channel is disarmed, on the
// channels asked, in as many frames as asked, with the telemetry bit; then
// motor stop again. Refused (counted) while armed; arming ends one.
TEST(PulseFirmwareDshot, SpecialCommandsOnlyWhileDisarmed) {
  constexpr int kChannels = 4;
  constexpr std::uint8_t kSpinReversed = 21;
  constexpr std::uint8_t kRepeat = 6;  // ESCs act on a setting after 6
  Host h;
  Escs esc(kChannels, 16.0 * 1e6 / 600e3);
  h.send_config(h.config(kChannels, 1000, 1000, MM_LINK_PROTOCOL_DSHOT600));
  h.board.run_for_us(3000);
  h.send_pulses({1000, 1000, 1000, 1000}, false);
  h.board.run_for_us(3000);
  esc.feed(h.board);
  for (DshotEsc& e : esc.escs) e.take_frames();
  h.send_command(kSpinReversed, 0b0110, kRepeat);
  h.board.run_for_us(20000);
  esc.feed(h.board);
  for (int ch = 0; ch < kChannels; ++ch) {
    int commands = 0;
    bool after = false, stop_after = true;
    for (const DshotFrame& f : esc.escs[static_cast<std::size_t>(ch)].take_frames()) {
      EXPECT_TRUE(f.crc_ok);
      if (f.value == kSpinReversed) {
        EXPECT_TRUE(f.telemetry);
        ++commands;
        after = true;
      } else {
        EXPECT_EQ(f.value, 0);
        if (after) stop_after &= f.value == 0;
      }
    }
    EXPECT_EQ(commands, (ch == 1 || ch == 2) ? kRepeat : 0) << "channel " << ch;
    EXPECT_TRUE(stop_after);
  }
  EXPECT_EQ(h.last_report().rejected, 0u);
  // Armed: refused and counted, no command frame.
  h.send_pulses({1200, 1200, 1200, 1200}, true);
  h.board.run_for_us(3000);
  h.send_command(kSpinReversed, 0b0001, kRepeat);
  h.board.run_for_us(15000);
  esc.feed(h.board);
  for (DshotEsc& e : esc.escs)
    for (const DshotFrame& f : e.take_frames()) EXPECT_NE(f.value, kSpinReversed);
  h.board.run_for_us(60000);
  EXPECT_EQ(h.last_report().rejected, 1u);
  // Disarmed again (after the link timeout above), a long command: the
  // first armed frame ends it.
  h.send_pulses({1000, 1000, 1000, 1000}, false);
  h.board.run_for_us(3000);
  h.send_command(kSpinReversed, 0b0001, 200);
  h.board.run_for_us(10000);
  h.send_pulses({1300, 1300, 1300, 1300}, true);
  h.board.run_for_us(5000);
  esc.feed(h.board);
  h.board.run_for_us(20000);
  esc.feed(h.board);
  const auto got = esc.escs[0].take_frames();
  ASSERT_FALSE(got.empty());
  EXPECT_EQ(got.back().value, throttle_for(1300.0));
  int commands = 0;
  for (const DshotFrame& f : got) commands += f.value == kSpinReversed ? 1 : 0;
  EXPECT_GT(commands, 0);
  EXPECT_LT(commands, 30);
}

}  // namespace
}  // namespace motormix::avr
