// The serial link to the pulse firmware (src/link/motormix_link.c,
// the same C both ends compile): frames round-trip; a parser fed 10^5
// corrupted frames (bit flips, truncation, a wrong CRC, random bytes) never
// accepts one with other content than what was sent, and counts them; it
// resynchronises on the next good frame. And the KISS / BLHeli_32 ESC
// telemetry frame: decoded, found in a stream by its CRC, corrupt frames
// refused and counted.

#include "kiss_esc_frame.hpp"
#include "output/kiss_telemetry.hpp"

#include "motormix_link.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace motormix::test {
namespace {

constexpr int kCorruptedFrames = 100000;

mm_link_pulses some_pulses(std::uint8_t seq, std::uint8_t count) {
  mm_link_pulses p{};
  p.session = 0x12345678U + seq;
  p.sequence = 0x80000000U + seq;
  p.armed = 1;
  p.count = count;
  for (std::uint8_t i = 0; i < count && i < MM_LINK_MAX_CHANNELS; ++i) {
    p.pulse_hus[i] = static_cast<std::uint16_t>(1000 + 97 * i + seq);
  }
  return p;
}

// Feeds bytes; the pulses of a PULSES frame that completed on byte i, if any.
bool feed_pulses(mm_link_parser& parser, std::uint8_t byte, mm_link_pulses& got) {
  mm_link_frame frame{};
  if (mm_link_feed(&parser, byte, &frame) != MM_LINK_PULSES) return false;
  got = frame.u.pulses;
  return true;
}

mm_link_config four_channel_config() {
  mm_link_config c{};
  c.session = 0xABCD0001U;
  c.sequence = 3;
  c.period_us = 2500;
  c.link_timeout_ms = 100;
  c.min_us = 1000;
  c.max_us = 2000;
  c.count = 4;
  for (int i = 0; i < 4; ++i) c.disarmed_us[i] = 1000;
  return c;
}

bool same(const mm_link_pulses& a, const mm_link_pulses& b) {
  if (a.session != b.session || a.sequence != b.sequence || a.armed != b.armed ||
      a.count != b.count || a.telemetry != b.telemetry)
    return false;
  for (std::uint8_t i = 0; i < a.count; ++i) {
    if (a.pulse_hus[i] != b.pulse_hus[i]) return false;
  }
  return true;
}

TEST(OutputLink, Crc32IsTheIeeeOne) {
  const char* check = "123456789";  // the catalogue's check value
  EXPECT_EQ(mm_link_crc32(0, reinterpret_cast<const std::uint8_t*>(check), 9), 0xCBF43926U);
}

TEST(OutputLink, PulsesAndReportsRoundTrip) {
  mm_link_parser parser;
  mm_link_parser_init(&parser);
  std::uint8_t buf[MM_LINK_MAX_FRAME];
  for (std::uint8_t count = 1; count <= MM_LINK_MAX_CHANNELS; ++count) {
    const mm_link_pulses sent = some_pulses(count, count);
    const std::size_t n = mm_link_encode_pulses(&sent, buf);
    ASSERT_EQ(n, 7u + MM_LINK_PULSES_BODY(count));
    mm_link_pulses got{};
    bool completed = false;
    for (std::size_t i = 0; i < n; ++i) completed = feed_pulses(parser, buf[i], got);
    EXPECT_TRUE(completed);
    EXPECT_TRUE(same(sent, got));
  }
  mm_link_report r{123456,         7, 8, 9, 1, 17, 0xF0000200U, MM_LINK_FLAG_CONFIGURED, 0x30002U,
                   MM_LINK_VERSION};
  std::size_t n = mm_link_encode_report(&r, 5, buf);
  mm_link_frame got{};
  std::uint8_t type = 0;
  for (std::size_t i = 0; i < n; ++i) type = mm_link_feed(&parser, buf[i], &got);
  EXPECT_EQ(type, MM_LINK_REPORT);
  EXPECT_EQ(got.u.report.frames, 123456U);
  EXPECT_EQ(got.u.report.rejected, 17);
  EXPECT_EQ(got.u.report.last_sequence, 0xF0000200U);
  EXPECT_EQ(got.u.report.flags, MM_LINK_FLAG_CONFIGURED);
  EXPECT_EQ(got.u.report.session, 0x30002U);
  EXPECT_EQ(got.u.report.version, MM_LINK_VERSION);
  const mm_link_config c = four_channel_config();
  n = mm_link_encode_config(&c, buf);
  ASSERT_EQ(n, 7u + MM_LINK_CONFIG_BODY(4));
  for (std::size_t i = 0; i < n; ++i) type = mm_link_feed(&parser, buf[i], &got);
  EXPECT_EQ(type, MM_LINK_CONFIG);
  EXPECT_EQ(got.u.config.session, 0xABCD0001U);
  EXPECT_EQ(got.u.config.sequence, 3U);
  EXPECT_EQ(got.u.config.period_us, 2500);
  EXPECT_EQ(got.u.config.max_us, 2000);
  EXPECT_EQ(got.u.config.disarmed_us[3], 1000);
  EXPECT_EQ(parser.crc_errors, 0U);
  mm_link_pulses bad = some_pulses(1, 8);
  bad.count = 9;
  EXPECT_EQ(mm_link_encode_pulses(&bad, buf), 0U);  // more channels than a frame carries
}

// The telemetry request (link version 5) rides in the count byte: every
// channel of every count round-trips, none means none, and a request beyond
// the count is neither sent nor taken; a frame of the same length is as
// long as one without (the chip's two-byte receive buffer sees no more).
TEST(OutputLink, TelemetryRequestsRoundTripInThePulsesFrame) {
  std::uint8_t buf[MM_LINK_MAX_FRAME];
  for (std::uint8_t count = 1; count <= MM_LINK_MAX_CHANNELS; ++count) {
    for (std::uint8_t ask = 0; ask <= count; ++ask) {
      mm_link_pulses sent = some_pulses(ask, count);
      sent.telemetry = ask;  // 0: none; c + 1: channel c
      const std::size_t n = mm_link_encode_pulses(&sent, buf);
      ASSERT_EQ(n, 7u + MM_LINK_PULSES_BODY(count));
      mm_link_parser parser;
      mm_link_parser_init(&parser);
      mm_link_pulses got{};
      bool completed = false;
      for (std::size_t i = 0; i < n; ++i) completed = feed_pulses(parser, buf[i], got);
      ASSERT_TRUE(completed) << "count " << int(count) << " ask " << int(ask);
      EXPECT_TRUE(same(got, sent)) << "count " << int(count) << " ask " << int(ask);
    }
    mm_link_pulses beyond = some_pulses(0, count);
    beyond.telemetry = static_cast<std::uint8_t>(count + 1);
    EXPECT_EQ(mm_link_encode_pulses(&beyond, buf), 0U);
  }
  // Received: a channel named without the flag, or beyond the count, is malformed.
  for (const std::uint8_t count_byte : {std::uint8_t{0x14}, std::uint8_t{0xC4}}) {
    mm_link_pulses p = some_pulses(0, 4);
    const std::size_t n = mm_link_encode_pulses(&p, buf);
    buf[3 + 10] = count_byte;  // after sync and length: type, session, sequence, armed, count
    // The CRC over length..payload, made again so only the content is wrong.
    const std::uint32_t crc = mm_link_crc32(0, buf + 2, n - 6);
    for (int b = 0; b < 4; ++b) buf[n - 4 + b] = static_cast<std::uint8_t>(crc >> (8 * b));
    mm_link_parser parser;
    mm_link_parser_init(&parser);
    mm_link_pulses got{};
    bool completed = false;
    for (std::size_t i = 0; i < n; ++i) completed = completed || feed_pulses(parser, buf[i], got);
    EXPECT_FALSE(completed) << std::hex << int(count_byte);
    EXPECT_EQ(parser.malformed, 1U) << std::hex << int(count_byte);
  }
}

TEST(OutputLink, ConfigurationsOutsideTheLimitsAreNeitherSentNorTaken) {
  {
    // The link timeout shorter than two periods: the chip's failsafe count
    // (timeout less a period) would wrap. 50 Hz with 10 ms, 40 Hz with 49 ms.
    mm_link_config c = four_channel_config();
    c.period_us = 20000;
    c.link_timeout_ms = 10;
    EXPECT_FALSE(mm_link_config_valid(&c));
    c.period_us = 25000;
    c.link_timeout_ms = 49;
    EXPECT_FALSE(mm_link_config_valid(&c));
    c.link_timeout_ms = 50;
    EXPECT_TRUE(mm_link_config_valid(&c));
  }
  std::uint8_t buf[MM_LINK_MAX_FRAME];
  const mm_link_config good = four_channel_config();
  EXPECT_EQ(mm_link_config_valid(&good), 1);
  auto with = [&](auto change) {
    mm_link_config c = good;
    change(c);
    return c;
  };
  const mm_link_config bad[] = {
      with([](mm_link_config& c) { c.period_us = 1999; }),   // faster than 500 Hz
      with([](mm_link_config& c) { c.period_us = 25001; }),  // slower than 40 Hz
      with([](mm_link_config& c) { c.max_us = 2480; }),      // no low time before the next period
      with([](mm_link_config& c) { c.min_us = 2100; }),      // min above max
      with([](mm_link_config& c) { c.disarmed_us[2] = 400; }),  // below any servo pulse
      with([](mm_link_config& c) { c.link_timeout_ms = 5; }),
      with([](mm_link_config& c) { c.link_timeout_ms = 1001; }),
      with([](mm_link_config& c) { c.count = 0; }),
      with([](mm_link_config& c) { c.count = 9; })};
  for (const mm_link_config& c : bad) {
    EXPECT_EQ(mm_link_config_valid(&c), 0);
    EXPECT_EQ(mm_link_encode_config(&c, buf), 0U);
  }
  // An invalid one built by hand (right CRC) is counted as malformed.
  const std::size_t n = mm_link_encode_config(&good, buf);
  buf[3 + 9] = 0x10;  // the period becomes 0x0110 = 272 us, then the CRC is made right
  buf[3 + 10] = 0x01;
  const std::uint32_t crc = mm_link_crc32(0, buf + 2, n - 6);
  for (int i = 0; i < 4; ++i) buf[n - 4 + i] = static_cast<std::uint8_t>(crc >> (8 * i));
  mm_link_parser parser;
  mm_link_parser_init(&parser);
  mm_link_frame got{};
  std::uint8_t type = 0;
  for (std::size_t i = 0; i < n; ++i) type = mm_link_feed(&parser, buf[i], &got);
  EXPECT_EQ(type, 0);
  EXPECT_EQ(parser.malformed, 1U);
  EXPECT_EQ(parser.crc_errors, 0U);
}

// DShot in CONFIG (link version 3) and the COMMAND frame: what goes is what
// comes back; what the firmware could not do is neither sent nor taken.
TEST(OutputLink, DshotConfigurationsAndCommandsRoundTripWithinTheirLimits) {
  std::uint8_t buf[MM_LINK_MAX_FRAME];
  mm_link_config dshot = four_channel_config();
  dshot.protocol = MM_LINK_PROTOCOL_DSHOT600;
  dshot.period_us = 500;  // 2 kHz frames: too fast for servo pulses, fine for DShot
  EXPECT_EQ(mm_link_config_valid(&dshot), 1);
  mm_link_parser parser;
  mm_link_parser_init(&parser);
  mm_link_frame got{};
  std::uint8_t type = 0;
  const std::size_t n = mm_link_encode_config(&dshot, buf);
  ASSERT_EQ(n, 7u + MM_LINK_CONFIG_BODY(4));
  for (std::size_t i = 0; i < n; ++i) type = mm_link_feed(&parser, buf[i], &got);
  ASSERT_EQ(type, MM_LINK_CONFIG);
  EXPECT_EQ(got.u.config.protocol, MM_LINK_PROTOCOL_DSHOT600);
  EXPECT_EQ(got.u.config.period_us, 500);
  auto with = [&](auto change) {
    mm_link_config c = dshot;
    change(c);
    return c;
  };
  const mm_link_config bad[] = {
      with([](mm_link_config& c) { c.protocol = 4; }),       // no such protocol
      with([](mm_link_config& c) { c.period_us = 249; }),    // faster than 4 kHz
      with([](mm_link_config& c) { c.count = 7; }),          // D2..D7 only
      with([](mm_link_config& c) { c.min_us = c.max_us; }),  // no throttle range
      with([](mm_link_config& c) { c.protocol = 0; }),       // servo pulses at 2 kHz
      with([](mm_link_config& c) {  // bidirectional DShot150: its replies outlast the window
        c.protocol = MM_LINK_PROTOCOL_DSHOT150 | MM_LINK_PROTOCOL_BIDIRECTIONAL;
        c.period_us = MM_LINK_MIN_BIDIR_PERIOD_US;
      }),
      with([](mm_link_config& c) {  // bidirectional faster than the chip decodes
        c.protocol = MM_LINK_PROTOCOL_DSHOT600 | MM_LINK_PROTOCOL_BIDIRECTIONAL;
      }),
      with([](mm_link_config& c) {  // bidirectional on five channels
        c.protocol = MM_LINK_PROTOCOL_DSHOT600 | MM_LINK_PROTOCOL_BIDIRECTIONAL;
        c.period_us = MM_LINK_MIN_BIDIR_PERIOD_US;
        c.count = 5;
        c.disarmed_us[4] = 1000;
      }),
      with([](mm_link_config& c) { c.protocol = 0x43; })};  // an unknown flag
  for (const mm_link_config& c : bad) {
    EXPECT_EQ(mm_link_config_valid(&c), 0);
    EXPECT_EQ(mm_link_encode_config(&c, buf), 0U);
  }

  mm_link_config bidir = dshot;
  bidir.protocol = MM_LINK_PROTOCOL_DSHOT300 | MM_LINK_PROTOCOL_BIDIRECTIONAL;
  bidir.period_us = MM_LINK_MIN_BIDIR_PERIOD_US;
  EXPECT_EQ(mm_link_config_valid(&bidir), 1);

  // TELEMETRY: readings of every channel; a count or reading count outside
  // the limits is not sent.
  mm_link_telemetry t{};
  t.first = 40000;
  t.readings = MM_LINK_TELEMETRY_MAX_READINGS;
  t.count = 4;
  for (int r = 0; r < t.readings; ++r)
    for (int c = 0; c < 4; ++c) t.period_us[r][c] = static_cast<std::uint16_t>(100 * r + c);
  const std::size_t tn = mm_link_encode_telemetry(&t, 3, buf);
  ASSERT_EQ(tn, 7u + MM_LINK_TELEMETRY_BODY(MM_LINK_TELEMETRY_MAX_READINGS, 4u));
  for (std::size_t i = 0; i < tn; ++i) type = mm_link_feed(&parser, buf[i], &got);
  ASSERT_EQ(type, MM_LINK_TELEMETRY);
  EXPECT_EQ(got.u.telemetry.first, 40000);
  EXPECT_EQ(got.u.telemetry.readings, MM_LINK_TELEMETRY_MAX_READINGS);
  EXPECT_EQ(got.u.telemetry.period_us[4][3], 403);
  mm_link_telemetry too_many = t;
  too_many.readings = MM_LINK_TELEMETRY_MAX_READINGS + 1;
  EXPECT_EQ(mm_link_encode_telemetry(&too_many, 3, buf), 0U);
  mm_link_telemetry five = t;
  five.count = 5;
  EXPECT_EQ(mm_link_encode_telemetry(&five, 3, buf), 0U);

  mm_link_command cmd{};
  cmd.session = 0xABCD0001U;
  cmd.sequence = 9;
  cmd.command = 21;
  cmd.channels = 0b0110;
  cmd.repeat = 6;
  const std::size_t m = mm_link_encode_command(&cmd, buf);
  ASSERT_EQ(m, 7u + MM_LINK_COMMAND_BODY);
  for (std::size_t i = 0; i < m; ++i) type = mm_link_feed(&parser, buf[i], &got);
  ASSERT_EQ(type, MM_LINK_COMMAND);
  EXPECT_EQ(got.u.command.session, cmd.session);
  EXPECT_EQ(got.u.command.sequence, cmd.sequence);
  EXPECT_EQ(got.u.command.command, 21);
  EXPECT_EQ(got.u.command.channels, 0b0110);
  EXPECT_EQ(got.u.command.repeat, 6);
  for (const int c : {0, 48, 255}) {  // throttle values are not commands
    mm_link_command b = cmd;
    b.command = static_cast<std::uint8_t>(c);
    EXPECT_EQ(mm_link_encode_command(&b, buf), 0U) << c;
  }
  mm_link_command none = cmd;
  none.channels = 0;
  EXPECT_EQ(mm_link_encode_command(&none, buf), 0U);
  EXPECT_EQ(parser.malformed + parser.crc_errors, 0U);
}
// A frame whose channel count disagrees with its length, with a good CRC
// (a host of another version, a bug): refused as malformed, never read with
// the count it claims (three channels read from four's bytes, or five from
// four's and the CRC's). `count_at`: the count's byte in the body, its low
// nibble for PULSES.
void expect_count_mismatch_refused(std::uint8_t* buf, std::size_t n, std::size_t count_at,
                                   std::uint8_t claimed, std::uint8_t mask) {
  std::uint8_t* body = buf + 3;
  body[count_at] = static_cast<std::uint8_t>((body[count_at] & ~mask) | claimed);
  const std::uint32_t crc = mm_link_crc32(0, buf + 2, static_cast<std::size_t>(buf[2]) + 1U);
  for (int i = 0; i < 4; ++i) buf[3 + buf[2] + i] = static_cast<std::uint8_t>(crc >> (8 * i));
  mm_link_parser parser;
  mm_link_parser_init(&parser);
  int taken = 0;
  for (std::size_t i = 0; i < n; ++i) {
    mm_link_frame frame{};
    taken += mm_link_feed(&parser, buf[i], &frame) != 0 ? 1 : 0;
  }
  EXPECT_EQ(taken, 0);
  EXPECT_EQ(parser.malformed, 1U);
  EXPECT_EQ(parser.crc_errors, 0U);
}

TEST(OutputLink, AFrameWhoseCountDisagreesWithItsLengthIsRefused) {
  for (const std::uint8_t claimed : {std::uint8_t{3}, std::uint8_t{5}}) {
    SCOPED_TRACE(static_cast<int>(claimed));
    std::uint8_t buf[MM_LINK_MAX_FRAME + 8];
    const mm_link_pulses pulses = some_pulses(1, 4);
    std::size_t n = mm_link_encode_pulses(&pulses, buf);
    ASSERT_EQ(buf[2], MM_LINK_PULSES_BODY(4));
    expect_count_mismatch_refused(buf, n, 10, claimed, 0x0F);
    const mm_link_config config = four_channel_config();
    n = mm_link_encode_config(&config, buf);
    ASSERT_EQ(buf[2], MM_LINK_CONFIG_BODY(4));
    expect_count_mismatch_refused(buf, n, 17, claimed, 0xFF);
  }
}

TEST(OutputLink, CorruptedFramesNeverChangeAPulseAndAreCounted) {
  std::mt19937 rng(20261204);
  mm_link_parser parser;
  mm_link_parser_init(&parser);
  std::uint8_t buf[MM_LINK_MAX_FRAME + 8];
  int accepted_changed = 0, good_accepted = 0;
  // The good frame sent after the previous corrupted one: the search after a
  // failure may hand it over a little late (the firmware's sequence check
  // then decides), never changed.
  mm_link_pulses previous_good = some_pulses(0, 4);
  for (int k = 0; k < kCorruptedFrames; ++k) {
    const mm_link_pulses sent =
        some_pulses(static_cast<std::uint8_t>(k), static_cast<std::uint8_t>(1 + k % 8));
    std::size_t n = mm_link_encode_pulses(&sent, buf);
    switch (k % 4) {
      case 0: {  // 1 to 8 bits flipped anywhere
        const int flips = 1 + static_cast<int>(rng() % 8);
        for (int f = 0; f < flips; ++f)
          buf[rng() % n] ^= static_cast<std::uint8_t>(1U << (rng() % 8));
        break;
      }
      case 1:  // truncated
        n = 1 + rng() % (n - 1);
        break;
      case 2:  // a wrong CRC
        buf[n - 1 - rng() % 4] ^= static_cast<std::uint8_t>(1 + rng() % 255);
        break;
      default:  // random bytes behind a valid sync
        for (std::size_t i = 2; i < n; ++i) buf[i] = static_cast<std::uint8_t>(rng());
        break;
    }
    mm_link_pulses got{};
    for (std::size_t i = 0; i < n; ++i) {
      if (feed_pulses(parser, buf[i], got) && !same(got, sent) && !same(got, previous_good)) {
        ++accepted_changed;
      }
    }
    // A good frame after each bad one: the parser finds its way back.
    const mm_link_pulses next = some_pulses(static_cast<std::uint8_t>(k + 1), 4);
    const std::size_t m = mm_link_encode_pulses(&next, buf);
    bool found = false;
    for (std::size_t i = 0; i < m; ++i) {
      if (!feed_pulses(parser, buf[i], got)) continue;
      if (same(got, next)) {
        found = true;
      } else if (!same(got, sent) && !same(got, previous_good)) {
        ++accepted_changed;
      }
    }
    if (found) ++good_accepted;
    previous_good = next;
  }
  EXPECT_EQ(accepted_changed, 0);
  // The search after a failure finds the next good frame (at the latest
  // with the bytes after it): nearly every one comes through.
  EXPECT_GT(good_accepted, kCorruptedFrames * 95 / 100);
  EXPECT_GT(parser.crc_errors + parser.malformed, static_cast<std::uint32_t>(kCorruptedFrames / 2));
}

TEST(KissTelemetry, DecodesAFrameAsKissDocumentsIt) {
  output::KissReading r;
  r.temperature_c = 41;
  r.voltage_v = 16.32;
  r.current_a = 12.5;
  r.consumption_mah = 734;
  r.erpm = 123400;
  const auto frame = kiss_esc_frame(r);
  EXPECT_EQ(frame[0], 41);
  EXPECT_EQ(frame[1], 0x06);  // 1632 = 0x0660
  EXPECT_EQ(frame[2], 0x60);
  output::KissTelemetryParser parser;
  output::KissReading got;
  bool ok = false;
  for (std::size_t i = 0; i < frame.size(); ++i)
    ok = parser.feed(frame[i], 10 * static_cast<std::int64_t>(i), got);
  ASSERT_TRUE(ok);
  EXPECT_DOUBLE_EQ(got.voltage_v, 16.32);
  EXPECT_DOUBLE_EQ(got.current_a, 12.5);
  EXPECT_DOUBLE_EQ(got.consumption_mah, 734);
  EXPECT_DOUBLE_EQ(got.erpm, 123400);
  EXPECT_EQ(parser.frames(), 1U);
}

TEST(KissTelemetry, FindsFramesInAStreamAndRefusesCorruptOnes) {
  std::mt19937 rng(4242);
  output::KissTelemetryParser parser;
  output::KissReading got;
  std::int64_t t = 0;
  int good = 0, sent_good = 0, wrong = 0;
  for (int k = 0; k < 20000; ++k) {
    output::KissReading r;
    r.temperature_c = 20 + k % 60;
    r.voltage_v = 14.0 + (k % 200) / 100.0;
    r.current_a = (k % 300) / 10.0;
    r.consumption_mah = k % 5000;
    r.erpm = 100.0 * (k % 600);
    auto frame = kiss_esc_frame(r);
    const bool corrupt = k % 3 == 0;
    if (corrupt) frame[rng() % frame.size()] ^= static_cast<std::uint8_t>(1U << (rng() % 8));
    if (!corrupt) ++sent_good;
    for (std::uint8_t b : frame) {
      t += 87;  // 115200 baud
      if (parser.feed(b, t, got)) {
        if (corrupt || std::abs(got.erpm - r.erpm) > 50.0 ||
            std::abs(got.voltage_v - r.voltage_v) > 0.005) {
          ++wrong;
        }
        ++good;
      }
    }
    t += 2500;  // the next request's gap
  }
  EXPECT_EQ(good, sent_good);
  EXPECT_EQ(wrong, 0);  // a single flipped bit never passes CRC-8
  EXPECT_GE(parser.rejected(), static_cast<std::uint64_t>(20000 / 3));
}

}  // namespace
}  // namespace motormix::test
