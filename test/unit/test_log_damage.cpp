// Damaged logs through `replay`: broken structure is skipped and reported,
// jumps in time never make the loop run across them, and the output stays
// bounded by the input.

#include "log/log_reader.hpp"
#include "log/log_replay.hpp"
#include "test_support.hpp"

#include <motormix/motor_pwm_t.hpp>

#include <lcm/lcm-cpp.hpp>

#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <sstream>

namespace motormix::test {
namespace {

using lcmlog::LogReader;
using lcmlog::ReplayOptions;
using lcmlog::ReplaySummary;

const std::string kFlight = "test/data/flights/team_quad.lcmlog";

std::vector<char> read_bytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

std::string write_bytes(const std::string& name, const std::vector<char>& bytes) {
  const std::string path = ::testing::TempDir() + "/" + name;
  std::ofstream(path, std::ios::binary)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  return path;
}

void put_be64(std::vector<char>& bytes, std::uint64_t at, std::int64_t value) {
  for (int i = 0; i < 8; ++i) {
    bytes[at + static_cast<std::uint64_t>(i)] =
        static_cast<char>((static_cast<std::uint64_t>(value) >> (56 - 8 * i)) & 0xFF);
  }
}

std::vector<lcmlog::LogEventView> events_of(const std::string& path) {
  LogReader r(path);
  std::vector<lcmlog::LogEventView> out;
  while (const auto* ev = r.next()) out.push_back(*ev);
  return out;
}

struct Replayed {
  bool ok = false;
  ReplaySummary summary;
  std::string log;
  std::uintmax_t bytes = 0;
};

Replayed replay(const std::string& in) {
  const auto config = team_quad_config();
  Replayed r;
  std::ostringstream log;
  const std::string out = in + ".out.lcmlog";
  r.ok = lcmlog::replay_log(config, in, out, ReplayOptions{}, r.summary, log);
  r.log = log.str();
  std::ifstream f(out, std::ios::binary | std::ios::ate);
  r.bytes = f ? static_cast<std::uintmax_t>(f.tellg()) : 0;
  return r;
}

// The reader sees exactly what LCM's own reader sees in an intact log.
TEST(LogReader, AgreesWithLcmOnAnIntactLog) {
  const auto ours = events_of(source_path(kFlight));
  lcm::LogFile theirs(source_path(kFlight), "r");
  std::size_t n = 0;
  while (const lcm::LogEvent* ev = theirs.readNextEvent()) {
    ASSERT_LT(n, ours.size());
    EXPECT_EQ(ours[n].timestamp, ev->timestamp);
    EXPECT_EQ(ours[n].channel, ev->channel);
    ASSERT_EQ(ours[n].data.size(), static_cast<std::size_t>(ev->datalen));
    EXPECT_EQ(0, std::memcmp(ours[n].data.data(), ev->data, ours[n].data.size()));
    ++n;
  }
  EXPECT_EQ(n, ours.size());
  LogReader again(source_path(kFlight));
  while (again.next()) {
  }
  EXPECT_TRUE(again.skipped().empty());
}

// Reading ahead (the replay's search for a reference channel) costs no
// second read and changes nothing next() returns: every event, in order.
TEST(LogReader, LookingAheadReturnsEveryEventOnceInOrder) {
  const auto all = events_of(source_path(kFlight));
  ASSERT_GT(all.size(), 100U);
  const auto same_as_all = [&](LogReader& r) {
    std::size_t n = 0;
    while (const auto* ev = r.next()) {
      EXPECT_EQ(ev->offset, all[n].offset);
      EXPECT_EQ(ev->channel, all[n].channel);
      ++n;
    }
    EXPECT_EQ(n, all.size());
  };
  LogReader absent(source_path(kFlight));
  EXPECT_FALSE(absent.look_ahead_for("NOT_IN_THE_LOG", std::numeric_limits<std::int64_t>::max(),
                                     all.size() + 1));
  EXPECT_EQ(absent.peek()->offset, all[0].offset);
  same_as_all(absent);
  // Found late, after a peek: still every event from the first.
  LogReader late(source_path(kFlight));
  ASSERT_NE(late.peek(), nullptr);
  EXPECT_TRUE(
      late.look_ahead_for(all[90].channel == all[0].channel ? all[0].channel : all[90].channel,
                          std::numeric_limits<std::int64_t>::max(), all.size()));
  same_as_all(late);
  // Bounded by count and by log time.
  LogReader few(source_path(kFlight));
  EXPECT_FALSE(few.look_ahead_for("NOT_IN_THE_LOG", std::numeric_limits<std::int64_t>::max(), 10));
  same_as_all(few);
  LogReader brief(source_path(kFlight));
  EXPECT_FALSE(brief.look_ahead_for("NOT_IN_THE_LOG", 1, all.size()));
  same_as_all(brief);
}

// A reference channel that first comes after the look-ahead: named in a
// warning and not compared; with --every-input (cycles after every input
// from the start) it is compared.
TEST(LogReader, AReferenceAfterTheLookAheadIsNamedOrComparedWithEveryInput) {
  const auto all = events_of(source_path(kFlight));
  const std::int64_t first = all.front().timestamp;
  const std::int64_t at =
      first + static_cast<std::int64_t>((lcmlog::kReferenceLookAheadS + 1.0) * 1e6);
  ASSERT_GT(all.back().timestamp, at) << "the flight is longer than the look-ahead";
  const std::string path = ::testing::TempDir() + "/late_reference.lcmlog";
  {
    lcm::LogFile out(path, "w");
    motormix::motor_pwm_t pwm{};
    pwm.num_motors = 4;
    pwm.command.assign(4, 0.5F);
    pwm.pwm.assign(4, 1500.0F);
    pwm.direction.assign(4, 0);
    pwm.armed = true;
    std::vector<std::uint8_t> bytes(static_cast<std::size_t>(pwm.getEncodedSize()));
    pwm.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    bool written = false;
    for (const auto& ev : all) {
      if (!written && ev.timestamp >= at) {
        lcm::LogEvent e{0, at, "PX4_MOTORS", static_cast<int32_t>(bytes.size()), bytes.data()};
        out.writeEvent(&e);
        written = true;
      }
      lcm::LogEvent e{0, ev.timestamp, ev.channel, static_cast<int32_t>(ev.data.size()),
                      const_cast<std::uint8_t*>(ev.data.data())};
      out.writeEvent(&e);
    }
  }
  const Replayed plain = replay(path);
  ASSERT_TRUE(plain.ok);
  EXPECT_FALSE(plain.summary.reference.present());
  EXPECT_NE(plain.log.find("PX4_MOTORS first appears"), std::string::npos) << plain.log;
  ReplayOptions every;
  every.cycle_on_every_input = true;
  ReplaySummary compared;
  std::ostringstream log;
  ASSERT_TRUE(
      lcmlog::replay_log(team_quad_config(), path, path + ".out.lcmlog", every, compared, log));
  ASSERT_TRUE(compared.reference.present());
  EXPECT_EQ(compared.reference.references, 1);
  std::remove(path.c_str());
}

// Three flipped bytes put one timestamp days ahead: that event is skipped,
// the replay goes on, and no cycle runs across the jump.
TEST(LogDamage, OneTimestampFarInTheFutureIsSkipped) {
  auto bytes = read_bytes(source_path(kFlight));
  const auto events = events_of(source_path(kFlight));
  const auto& victim = events[events.size() / 2];
  for (int i = 0; i < 3; ++i) bytes[victim.offset + 12 + 2 + static_cast<std::uint64_t>(i)] ^= 0x5A;
  const Replayed intact = replay(write_bytes("intact.lcmlog", read_bytes(source_path(kFlight))));
  const Replayed r = replay(write_bytes("future.lcmlog", bytes));
  ASSERT_TRUE(r.ok) << r.log;
  EXPECT_FALSE(r.summary.damaged());
  EXPECT_EQ(r.summary.discontinuities, 1);
  EXPECT_EQ(r.summary.skipped_events, 1);
  EXPECT_NE(r.log.find("byte " + std::to_string(victim.offset)), std::string::npos) << r.log;
  EXPECT_EQ(r.summary.outputs, intact.summary.outputs);
  EXPECT_LE(r.bytes, intact.bytes);
  EXPECT_NEAR(r.summary.duration_s, intact.summary.duration_s, 1e-9);
}

// Timestamps at the ends of the int64 range (found by fuzzing: the time
// arithmetic overflowed) are skipped as damaged.
TEST(LogDamage, ExtremeTimestampsAreSkipped) {
  auto bytes = read_bytes(source_path(kFlight));
  const auto events = events_of(source_path(kFlight));
  put_be64(bytes, events[0].offset + 12, std::numeric_limits<std::int64_t>::min());
  put_be64(bytes, events[10].offset + 12, std::numeric_limits<std::int64_t>::max());
  put_be64(bytes, events[11].offset + 12, -5);
  const Replayed intact = replay(write_bytes("intact5.lcmlog", read_bytes(source_path(kFlight))));
  const Replayed r = replay(write_bytes("extreme.lcmlog", bytes));
  ASSERT_TRUE(r.ok) << r.log;
  EXPECT_EQ(r.summary.skipped_events, 3);
  EXPECT_EQ(r.summary.input_events, intact.summary.input_events - 3);
  EXPECT_NE(r.log.find("outside any plausible time"), std::string::npos) << r.log;
  EXPECT_LE(r.summary.outputs, intact.summary.outputs);
}

// The whole second half shifted by a day (a logger paused) or back by a day:
// a new segment, the mixer restarts disarmed, and the output covers only the
// time actually in the log.
TEST(LogDamage, JumpsForwardAndBackStartNewSegmentsWithoutCyclesAcross) {
  const auto events = events_of(source_path(kFlight));
  const Replayed intact = replay(write_bytes("intact2.lcmlog", read_bytes(source_path(kFlight))));
  for (const std::int64_t shift : {86400LL * 1000000LL, -86400LL * 1000000LL}) {
    auto bytes = read_bytes(source_path(kFlight));
    for (std::size_t i = events.size() / 2; i < events.size(); ++i) {
      put_be64(bytes, events[i].offset + 12, events[i].timestamp + shift);
    }
    const Replayed r = replay(write_bytes("shifted.lcmlog", bytes));
    ASSERT_TRUE(r.ok) << r.log;
    EXPECT_EQ(r.summary.discontinuities, 1) << r.log;
    EXPECT_EQ(r.summary.skipped_events, 0);
    EXPECT_NE(r.log.find("new segment"), std::string::npos);
    // At most one extra tail of cycles (the first segment's) beyond the intact replay.
    const auto config = team_quad_config();
    const double tail_cycles = 2.0 * 0.1 * config.loop_rate_hz + 2;
    EXPECT_LE(static_cast<double>(r.summary.outputs),
              static_cast<double>(intact.summary.outputs) + tail_cycles);
    EXPECT_EQ(r.summary.input_events, intact.summary.input_events);
  }
}

// A broken event header in the middle: LCM's reader stops there; ours skips
// that event, carries on, and says which bytes it skipped.
TEST(LogDamage, BrokenHeaderIsSkippedAndReported) {
  auto bytes = read_bytes(source_path(kFlight));
  const auto events = events_of(source_path(kFlight));
  const auto& victim = events[events.size() / 3];
  bytes[victim.offset] = 0x00;  // sync word broken
  const Replayed r = replay(write_bytes("broken.lcmlog", bytes));
  ASSERT_TRUE(r.ok) << r.log;
  ASSERT_TRUE(r.summary.damaged());
  ASSERT_EQ(r.summary.skipped.size(), 1U);
  EXPECT_EQ(r.summary.skipped[0].begin, victim.offset);
  EXPECT_EQ(r.summary.skipped[0].end, events[events.size() / 3 + 1].offset);
  EXPECT_NE(r.log.find("is damaged: bytes " + std::to_string(victim.offset)), std::string::npos);
  const Replayed intact = replay(write_bytes("intact3.lcmlog", read_bytes(source_path(kFlight))));
  EXPECT_EQ(r.summary.input_events + r.summary.other_events + 1,
            intact.summary.input_events + intact.summary.other_events);
}

TEST(LogDamage, TruncatedLastEventAndGarbage) {
  auto bytes = read_bytes(source_path(kFlight));
  const auto events = events_of(source_path(kFlight));
  bytes.resize(static_cast<std::size_t>(events.back().offset) + 20);
  const Replayed cut = replay(write_bytes("cut.lcmlog", bytes));
  ASSERT_TRUE(cut.ok) << cut.log;
  ASSERT_EQ(cut.summary.skipped.size(), 1U);
  EXPECT_EQ(cut.summary.skipped[0].begin, events.back().offset);
  EXPECT_EQ(cut.summary.skipped[0].end, bytes.size());

  std::mt19937 rng(7);
  std::vector<char> noise(200000);
  for (char& c : noise) c = static_cast<char>(rng());
  const Replayed garbage = replay(write_bytes("garbage.lcmlog", noise));
  EXPECT_FALSE(garbage.ok);
  EXPECT_NE(garbage.log.find("holds no valid events"), std::string::npos) << garbage.log;
  const Replayed empty = replay(write_bytes("empty.lcmlog", {}));
  EXPECT_FALSE(empty.ok);
}

// Random damage anywhere (seeded): replay never crashes, and the output is
// bounded as documented: one cycle per loop period of the time its segments
// cover, and those never span more than the intact log plus, per
// discontinuity, one allowed gap and one tail.
TEST(LogDamage, RandomCorruptionStaysBounded) {
  const auto original = read_bytes(source_path(kFlight));
  const Replayed intact = replay(write_bytes("intact4.lcmlog", original));
  std::mt19937_64 rng(20261124);
  const auto config = team_quad_config();
  const double tail_s = 2.0 * 0.1;
  const double max_gap_s = ReplayOptions{}.max_gap_s;
  for (int trial = 0; trial < 40; ++trial) {
    auto bytes = original;
    const int flips = 1 + static_cast<int>(rng() % 20);
    for (int f = 0; f < flips; ++f) bytes[rng() % bytes.size()] = static_cast<char>(rng());
    const Replayed r = replay(write_bytes("random.lcmlog", bytes));
    if (!r.ok) continue;
    SCOPED_TRACE("trial " + std::to_string(trial));
    const double segments = static_cast<double>(r.summary.discontinuities + 1);
    EXPECT_LE(static_cast<double>(r.summary.outputs),
              config.loop_rate_hz * r.summary.duration_s + segments);
    EXPECT_LE(r.summary.duration_s, intact.summary.duration_s + segments * (max_gap_s + tail_s));
  }
}

}  // namespace
}  // namespace motormix::test
