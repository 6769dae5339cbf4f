// End to end, no hardware: the pulse firmware in simavr, in real time behind
// a pseudo-terminal (realtime_bridge.hpp), driven by `motormix output` over
// its serial driver, on a private bus.
// - A publisher standing in for the mixer sends motor_pwm_t at 400 Hz, each
//   message's channel 0 unique, so every pulse period names the message it
//   carries: pulse error against motor_pwm_t's values, and bus-to-pin
//   latency (publish to rising edge), p50 and p99.
// - The publisher stops (a mixer killed): time to disarmed pulses.
// - `motormix output` is SIGKILLed: time to disarmed pulses (the firmware's
//   own link watchdog).
// - The real chain: `motormix run` flies the bundled team-quad flight from
//   lcm-logplayer, and the pulses follow its motor_pwm_t; then the mixer is
//   SIGKILLed.
// Times are the simulated chip's, mapped to the wall clock; the bridge
// reports how far the simulation ever fell behind, and the test asks that
// to stay small so the numbers mean what they say.

#include "dshot_esc.hpp"
#include "integration/process.hpp"
#include "realtime_bridge.hpp"
#include "test_paths.hpp"
#include "test_support.hpp"

#include <motormix/motor_pwm_t.hpp>
#include <motormix/output_status_t.hpp>

#include <lcm/lcm-cpp.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#ifndef MOTORMIX_FIRMWARE_ELF
#error "MOTORMIX_FIRMWARE_ELF: the firmware under test"
#endif

namespace motormix::test {
namespace {

// The chip's receiver kept up with what motormix output sent, at the real
// ATmega328P's depth (AvrBoard::kReceiveDepth): no byte a real chip would
// have lost.
void expect_receiver_kept_up(avr::RealtimeBridge& bridge) {
  const avr::RealtimeBridge::Receiver rx = bridge.receiver();
  EXPECT_EQ(rx.overruns, 0) << "bytes a real ATmega328P's receiver would have lost";
}

using avr::steady_us;
using avr::TimedPulse;

constexpr double kPulseToleranceUs = 1.0;  // the bound
constexpr double kDisarmedUs = 1000.0;
// The simulated chip runs about three times faster than real time on a
// quiet machine, so a busy moment on the host only makes it late for a
// while; on a machine busy for long (two other jobs on the two cores, or a
// CI run beside other work: the chip kept half of real time) it is absent
// for much of the run (RealtimeBridge::absent_us: its clock stood still).
// (a VM whose host takes its CPU away: 17 % of the run's CPU time stolen,
// the chip absent 1.4 s of 3 s, seen here). Latency and skipped messages
// are judged only where the chip ran from kJudgeMarginUs before to
// kJudgeMarginUs after them, and need kMinJudged such samples (fewer: the
// machine was too busy to say anything of timing, and the run fails);
// which message a pulse or frame carries is looked for back to 10 ms
// before it plus the time the chip was absent before it; counts are of
// what the chip could do in the time it ran; failsafe bounds add the time
// it was absent in their window. The chip's own timing is
// test_pulse_firmware's, cycle-exact.
constexpr std::int64_t kJudgeMarginUs = 3000;
constexpr int kMinJudged = 100;
constexpr std::int64_t kCarriedWithinUs = 10000;
constexpr double kMixerDeathBoundMs = 100.0;   // output's 50 ms staleness + frames + a period
constexpr double kOutputDeathBoundMs = 100.0;  // the firmware's link timeout
// Bus to pin, the median over every armed period: up to a period's wait for
// the next rise, the frame on the wire (about 1 ms at 250000 baud) and the
// host's part (p99 under 0.2 ms in the bench); measured 1.3-3.2 ms.
// A constant 8 ms delay in the chain fails it; the median is not moved by
// the machine's scheduling stalls (the p99 is printed: 1.7-6.1 ms measured).
// The synthetic test's chip runs at 490 Hz while its messages come at 400
// Hz: every message spans more than a period, so a correct chain carries
// each one, whatever the two clocks' phase (at one rate, a phase where the
// messages come in right at the rises has the host's jitter push two into
// one period now and then: up to 20 % skipped). The team quad flight keeps
// both at 400 Hz, in step, as a vehicle flies.
constexpr int kSyntheticPulseRateHz = 490;
constexpr double kPeriodMs = 1000.0 / kSyntheticPulseRateHz;
constexpr double kFlightPeriodMs = 2.5;
constexpr double kLatencyP50BoundMs = kPeriodMs + 1.0 + 1.0;
// Pulses held on one message while newer ones were published: at most two
// periods beyond the simulated chip's own lag. Runs of 11-76 ms were the
// firmware's double buffer (a frame taken while a period started was held
// back, and the next one went into the same buffer again: host frames in
// step with the period held the pins as long as the phase held); found with
// the frames read off the pty against the chip's reports (every frame taken,
// none refused), fixed with a third buffer, and pinned down cycle-exact by
// test_pulse_firmware's FramesInStepWithThePeriodAreTakenAtTheNextRise.
constexpr double kHeldPeriods = 2.0;
// The sanitized build runs motormix run and output two to three times
// slower: their scheduling adds to how long the pins hold one frame (0.28
// ms over two periods once under ASan with the chip keeping real time;
// never in Release). Real-time bounds are Release's; ASan's run is for
// memory errors.
#if defined(__SANITIZE_ADDRESS__)
constexpr double kHeldSlackMs = 1.0;
#else
constexpr double kHeldSlackMs = 0.0;
#endif
// Armed periods whose pulses are a motor_pwm_t published in the 10 ms before
// (plus the chip's lag). With the fix: 99.6-100 % over ten runs (88-100 %
// before). A chain that stops following fails it; a constant delay,
// dropped messages and a failsafe that arms again fail the synthetic test's
// checks (median latency, share of messages carried, no armed period after
// the first disarmed one).
constexpr double kMatchedShare = 0.99;
// Of the synthetic test's messages, those skipped alone (the one before and
// the one after carried): a chain that drops messages does this (one in six
// dropped: 16 %), while the machine's stalls skip runs of them (after a
// stall the output writes only the newest message it took), which are not
// counted. With the chip faster than the messages only the host's jitter
// beyond 0.45 ms skips one: measured 0-0.5 %.
constexpr double kLoneSkipsShare = 0.03;
// A message's publication time against the chip's rise: clocks read in
// different processes and threads.
constexpr std::int64_t kReceiveSlackUs = 1000;

// Judged for timing: the chip ran throughout [from - margin, to + margin].
bool judged(avr::RealtimeBridge& bridge, std::int64_t from_us, std::int64_t to_us) {
  return bridge.present(from_us - kJudgeMarginUs, to_us + kJudgeMarginUs);
}

// How far back from `at_us` a message it carries may have been published:
// kCarriedWithinUs of the chip's time, and the wall time it was absent in
// the 100 ms before (the bytes waited in the pseudo-terminal).
std::int64_t carried_from(avr::RealtimeBridge& bridge, std::int64_t at_us) {
  return at_us - kCarriedWithinUs - bridge.absent_us(at_us - 100000, at_us);
}

// The time the chip was absent in a failsafe's window, ms (NaN and
// negative times, which fail by themselves, add nothing).
double absent_ms(avr::RealtimeBridge& bridge, std::int64_t from_us, double after_ms) {
  if (!(after_ms > 0.0)) return 0.0;
  return static_cast<double>(
             bridge.absent_us(from_us, from_us + static_cast<std::int64_t>(after_ms * 1000.0))) /
         1000.0;
}

const char* const kTooBusy =
    "the machine was too busy to run the simulated chip in real time: too little of the run "
    "can be judged";

std::string write_config(const std::string& device) {
  const std::string path = "/tmp/motormix-e2e-" + std::to_string(::getpid()) + ".yaml";
  std::ofstream(path) << "name: e2e\n"
                         "geometry: {preset: quad_x}\n"
                         "output: {min: 1000, max: 2000, disarmed: 1000}\n"
                         "hardware:\n"
                         "  driver: serial\n"
                         "  pulse_rate_hz: "
                      << kSyntheticPulseRateHz
                      << "\n"
                         "  serial: {device: "
                      << device << "}\n";
  return path;
}

// One period's pulses: every channel rose together.
struct Period {
  std::int64_t rise_us;
  std::map<int, double> width;
};

std::vector<Period> periods_of(const std::vector<TimedPulse>& pulses) {
  std::map<std::uint64_t, Period> by_rise;
  for (const TimedPulse& p : pulses) {
    Period& period = by_rise[p.rise_cycle];
    if (period.width.empty()) period.rise_us = p.rise_wall_us;
    period.rise_us = std::max(period.rise_us, p.rise_wall_us);  // the latest view of the rise
    period.width[p.channel] = p.width_us;
  }
  std::vector<Period> out;
  for (auto& [rise, period] : by_rise)
    if (period.width.size() == 4) out.push_back(period);
  return out;
}

bool disarmed(const Period& p) {
  for (const auto& [ch, w] : p.width)
    if (std::abs(w - kDisarmedUs) > kPulseToleranceUs) return false;
  return true;
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))];
}

// The first disarmed period rising after `after_us`, in ms after it; NaN
// if none, and -1 if an armed period came after it (a failsafe that
// disarms for a period and arms again is no failsafe).
double ms_to_disarmed(const std::vector<Period>& periods, std::int64_t after_us) {
  double first = NAN;
  for (const Period& p : periods) {
    if (p.rise_us <= after_us) continue;
    if (std::isnan(first)) {
      if (disarmed(p)) first = static_cast<double>(p.rise_us - after_us) / 1000.0;
    } else if (!disarmed(p)) {
      return -1.0;
    }
  }
  return first;
}

// A message the held period cannot be carrying: some channel more than the
// pulse tolerance away (the chip makes widths in half microseconds, so
// messages a fraction of a microsecond apart give the same pulses).
bool differs(const Period& held, const std::vector<float>& pwm) {
  for (const auto& [ch, w] : held.width)
    if (std::abs(w - pwm[static_cast<std::size_t>(ch)]) > kPulseToleranceUs) return true;
  return false;
}

bool same_widths(const Period& a, const Period& b) {
  for (const auto& [ch, w] : a.width)
    if (std::abs(w - b.width.at(ch)) > kPulseToleranceUs / 4) return false;
  return true;
}

// Runs of armed periods held on one set of widths while messages with other
// values were published: the longest such run, in ms from the first
// message that should have replaced it to the run's last rise. `published`
// gives, for a time span, whether a message with other widths came in it.
template <typename OtherPublished>
double longest_stall_ms(const std::vector<Period>& periods, std::int64_t until_us,
                        const OtherPublished& other_published) {
  double longest = 0.0;
  std::size_t i = 0;
  while (i < periods.size()) {
    std::size_t j = i;
    while (j + 1 < periods.size() && periods[j + 1].rise_us <= until_us &&
           !disarmed(periods[j + 1]) && same_widths(periods[i], periods[j + 1]))
      ++j;
    if (!disarmed(periods[i]) && periods[i].rise_us <= until_us && j > i) {
      const std::int64_t newer =
          other_published(periods[i], periods[i].rise_us, periods[j].rise_us);
      if (newer >= 0) {
        const double held = static_cast<double>(periods[j].rise_us - newer) / 1000.0;
        longest = std::max(longest, held);
      }
    }
    i = j + 1;
  }
  return longest;
}

TEST(OutputEndToEnd, PulsesFollowMotorPwmAndFailSafeWhenEitherProcessDies) {
  avr::RealtimeBridge bridge(MOTORMIX_FIRMWARE_ELF);
  const std::string config = write_config(bridge.device());
  auto output = std::make_unique<ChildProcess>(
      std::vector<std::string>{motormix_binary(), "output", "--config", config},
      "/tmp/motormix-e2e-output.log");
  lcm::LCM lcm;
  ASSERT_TRUE(lcm.good());
  // motormix output's status: the chip's report reaches the bus.
  struct StatusTaker {
    std::optional<motormix::output_status_t> last;
    void on(const lcm::ReceiveBuffer*, const std::string&, const motormix::output_status_t* m) {
      last = *m;
    }
  } statuses;
  lcm.subscribe("OUTPUT_STATUS", &StatusTaker::on, &statuses)->setQueueCapacity(1000);
  std::this_thread::sleep_for(std::chrono::milliseconds(600));  // configured: disarmed pulses
  for (int i = 0; i < 100000 && lcm.handleTimeout(0) > 0; ++i) {
  }
  // What the chip counted before the run (the line opening may cost a frame).
  const std::int64_t malformed_before =
      statuses.last && statuses.last->firmware_report ? statuses.last->firmware_malformed : 0;
  const std::int64_t crc_before =
      statuses.last && statuses.last->firmware_report ? statuses.last->firmware_crc_errors : 0;
  bridge.take_pulses();
  bridge.reset_max_lag();  // from here the timings count

  // 3 s of motor_pwm_t at 400 Hz, channel 0 unique per message (k % 800).
  std::map<int, std::int64_t> published_us;  // k -> when
  std::map<int, std::vector<float>> values;
  const int kMessages = 1200;
  const auto start = std::chrono::steady_clock::now();
  for (int k = 0; k < kMessages; ++k) {
    motormix::motor_pwm_t m{};
    m.num_motors = 4;
    m.pwm = {1100.25f + static_cast<float>(k % 800), 1300.0f + 0.37f * static_cast<float>(k % 1000),
             1500.5f + static_cast<float>((k * 7) % 300) * 0.73f,
             1450.0f + 0.11f * static_cast<float>(k % 2000)};
    m.command.assign(4, 0.5f);
    m.direction.assign(4, 0);
    m.armed = true;
    m.utime = k;
    std::this_thread::sleep_until(start + std::chrono::microseconds(2500 * k));
    published_us[k] = steady_us();
    values[k] = m.pwm;
    lcm.publish("MOTOR_PWM", &m);
  }
  const std::int64_t last_publish = steady_us();
  bridge.wait_chip_time(last_publish, 200.0);  // the "mixer" is gone
  const std::vector<Period> run = periods_of(bridge.take_pulses());

  // Each armed period: the message whose channel 0 it carries (the latest
  // such published before its rise).
  std::vector<double> errors, latency_ms;
  std::map<int, bool> seen;
  double worst = 0.0;
  for (const Period& p : run) {
    // After the last message the output holds it until its staleness
    // timeout (measured below, mixer_gone_ms), not latency.
    if (disarmed(p) || p.rise_us > last_publish) continue;
    // Channel 0 says which message, to a microsecond (grouped edges move a
    // pulse by up to half of one): of the messages it could be, published
    // before the rise, the one the whole period matches best.
    const int code = static_cast<int>(std::lround(p.width.at(0) - 1100.25));
    int k = -1;
    double best = 1e9;
    for (int c0 = code - 1; c0 <= code + 1; ++c0) {
      for (int c = (c0 % 800 + 800) % 800; c < kMessages; c += 800) {
        if (published_us[c] >= p.rise_us) continue;
        double e = 0.0;
        for (int ch = 0; ch < 4; ++ch)
          e = std::max(e, std::abs(p.width.at(ch) - values[c][static_cast<std::size_t>(ch)]));
        if (e < best || (e == best && c > k)) {
          best = e;
          k = c;
        }
      }
    }
    ASSERT_GE(k, 0) << "a period carrying no message: channel 0 " << p.width.at(0);
    for (int ch = 0; ch < 4; ++ch) {
      const double err = p.width.at(ch) - values[k][static_cast<std::size_t>(ch)];
      worst = std::max(worst, std::abs(err));
      errors.push_back(std::abs(err));
    }
    // Every period carrying it, not only its first: a chain that holds a
    // message for long shows there.
    if (judged(bridge, published_us[k], p.rise_us))
      latency_ms.push_back(static_cast<double>(p.rise_us - published_us[k]) / 1000.0);
    seen[k] = true;
  }
  const double mixer_gone_ms = ms_to_disarmed(run, last_publish);
  const double held_ms =
      longest_stall_ms(run, last_publish,
                       [&](const Period& held, std::int64_t from, std::int64_t to) -> std::int64_t {
                         for (const auto& [k, at] : published_us) {
                           if (at > from && at < to && differs(held, values[k])) return at;
                         }
                         return -1;
                       });
  std::printf(
      "%zu armed periods carried %zu of %d messages; pulse error p50 %.3f us, worst %.3f "
      "us; bus to pin p50 %.2f ms, p99 %.2f ms; held at most %.2f ms; disarmed %.1f ms after "
      "the last motor_pwm_t; chip late by %.2f ms at worst\n",
      errors.size() / 4, seen.size(), kMessages, percentile(errors, 0.5), worst,
      percentile(latency_ms, 0.5), percentile(latency_ms, 0.99), held_ms, mixer_gone_ms,
      bridge.max_lag_us() / 1000.0);
  EXPECT_LE(worst, kPulseToleranceUs);
  int lone_skips = 0, judged_messages = 0;
  for (int k = 1; k + 1 < kMessages; ++k) {
    if (!judged(bridge, published_us[k - 1], published_us[k + 1])) continue;
    ++judged_messages;
    lone_skips += !seen.count(k) && seen.count(k - 1) && seen.count(k + 1) ? 1 : 0;
  }
  std::printf("%d of %d messages judged (the chip running around them) skipped alone\n", lone_skips,
              judged_messages);
  ASSERT_GE(judged_messages, kMinJudged) << kTooBusy;
  EXPECT_LE(static_cast<double>(lone_skips), judged_messages * kLoneSkipsShare);
  // The median without the chip's worst lag: lag comes in short episodes
  // that do not move it.
  EXPECT_LE(percentile(latency_ms, 0.5), kLatencyP50BoundMs);
  EXPECT_LE(held_ms, kHeldPeriods * kPeriodMs + kHeldSlackMs + bridge.max_lag_us() / 1000.0);
  EXPECT_GT(mixer_gone_ms, 0.0) << "armed again after disarming, or never disarmed";
  EXPECT_LE(mixer_gone_ms, kMixerDeathBoundMs + absent_ms(bridge, last_publish, mixer_gone_ms));
  // Everything queued (this process hears its own motor_pwm_t too), then a
  // fresh status (10 Hz).
  for (int i = 0; i < 100000 && lcm.handleTimeout(0) > 0; ++i) {
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(250));
  for (int i = 0; i < 100000 && lcm.handleTimeout(0) > 0; ++i) {
  }
  ASSERT_TRUE(statuses.last.has_value()) << "no output_status_t";
  const motormix::output_status_t& st = *statuses.last;
  std::printf(
      "output_status_t: taken %lld, firmware frames %lld, crc errors %lld (%lld before the run), "
      "malformed %lld (%lld before), flags %d\n",
      static_cast<long long>(st.taken), static_cast<long long>(st.firmware_frames),
      static_cast<long long>(st.firmware_crc_errors), static_cast<long long>(crc_before),
      static_cast<long long>(st.firmware_malformed), static_cast<long long>(malformed_before),
      st.firmware_flags);
  EXPECT_EQ(st.driver, motormix::output_status_t::DRIVER_SERIAL);
  EXPECT_EQ(st.pins, motormix::output_status_t::PINS_STALE);  // the "mixer" went quiet
  EXPECT_GE(st.taken, kMessages * 9 / 10);
  ASSERT_TRUE(st.firmware_report);
  // The output writes a frame at least every 20 ms (its keep-alive), and
  // has run for at least the 3.8 s above.
  EXPECT_GE(st.firmware_frames, 3800 / 20);
  // The run itself: no frame lost to its CRC or its length.
  EXPECT_EQ(st.firmware_crc_errors - crc_before, 0);
  EXPECT_EQ(st.firmware_malformed - malformed_before, 0);
  EXPECT_EQ(st.firmware_link_timeouts, 0);
  EXPECT_EQ(st.firmware_watchdog_resets, 0);
  EXPECT_TRUE(st.firmware_flags & motormix::output_status_t::FIRMWARE_CONFIGURED);

  // Armed again, then the output process killed outright.
  for (int k = 0; k < 200; ++k) {
    motormix::motor_pwm_t m{};
    m.num_motors = 4;
    m.pwm.assign(4, 1600.0f);
    m.command.assign(4, 0.6f);
    m.direction.assign(4, 0);
    m.armed = true;
    lcm.publish("MOTOR_PWM", &m);
    std::this_thread::sleep_for(std::chrono::microseconds(2500));
    if (k == 150) {
      output->signal(SIGKILL);
    }
  }
  const std::int64_t killed = steady_us() - 49 * 2500;  // when k == 150 was
  bridge.wait_chip_time(killed, 200.0);
  const std::vector<Period> after = periods_of(bridge.take_pulses());
  const double output_gone_ms = ms_to_disarmed(after, killed);
  std::printf(
      "disarmed %.1f ms after SIGKILL of motormix output; the simulation fell behind the "
      "wall clock by %.2f ms at worst\n",
      output_gone_ms, bridge.max_lag_us() / 1000.0);
  EXPECT_LE(output_gone_ms, kOutputDeathBoundMs + absent_ms(bridge, killed, output_gone_ms));
  EXPECT_GT(output_gone_ms, 0.0);
  expect_receiver_kept_up(bridge);
  std::remove(config.c_str());
}

// DShot600 at 1 kHz through motormix output: what emulated ESCs decode
// from the pins is the throttle of a motor_pwm_t published just before,
// every frame with a good checksum; motor stop once the messages stop
// (the output's staleness) and once the output is SIGKILLed (the chip's
// link timeout).
TEST(OutputEndToEnd, DshotFramesFollowMotorPwmAndStopWhenEitherProcessDies) {
  constexpr int kMotors = 4;
  constexpr double kBitCycles = 16.0 * 1e6 / 600e3;
  constexpr double kFrameMs = 1.0;  // 1 kHz
  avr::RealtimeBridge bridge(MOTORMIX_FIRMWARE_ELF);
  const std::string config = "/tmp/motormix-e2e-dshot-" + std::to_string(::getpid()) + ".yaml";
  std::ofstream(config) << "name: e2e-dshot\n"
                           "geometry: {preset: quad_x}\n"
                           "output: {min: 1000, max: 2000, disarmed: 1000}\n"
                           "hardware:\n"
                           "  driver: serial\n"
                           "  protocol: dshot600\n"
                           "  pulse_rate_hz: 1000\n"
                           "  serial: {device: "
                        << bridge.device() << "}\n";
  auto output = std::make_unique<ChildProcess>(
      std::vector<std::string>{motormix_binary(), "output", "--config", config},
      "/tmp/motormix-e2e-dshot-output.log");
  lcm::LCM lcm;
  ASSERT_TRUE(lcm.good());
  std::this_thread::sleep_for(std::chrono::milliseconds(600));  // configured: motor stop
  bridge.take_edges();
  bridge.reset_max_lag();
  // What the firmware makes of a width: half microseconds, [1000, 2000]
  // onto 48..2047.
  auto throttle = [](float pwm) {
    const long hus = std::clamp(std::lround(2.0 * static_cast<double>(pwm)), 2000L, 4000L);
    return static_cast<int>(48 + ((hus - 2000) * 1999 + 1000) / 2000);
  };
  std::map<int, std::int64_t> published_us;
  std::map<int, std::vector<int>> expected;
  const int kMessages = 1200;
  const auto start = std::chrono::steady_clock::now();
  for (int k = 0; k < kMessages; ++k) {
    motormix::motor_pwm_t m{};
    m.num_motors = kMotors;
    m.pwm = {1100.25f + static_cast<float>(k % 800), 1300.0f + 0.37f * static_cast<float>(k % 1000),
             1500.5f + static_cast<float>((k * 7) % 300) * 0.73f,
             1450.0f + 0.11f * static_cast<float>(k % 2000)};
    m.command.assign(kMotors, 0.5f);
    m.direction.assign(kMotors, 0);
    m.armed = true;
    std::this_thread::sleep_until(start + std::chrono::microseconds(2500 * k));
    published_us[k] = steady_us();
    for (float v : m.pwm) expected[k].push_back(throttle(v));
    lcm.publish("MOTOR_PWM", &m);
  }
  const std::int64_t first_publish = published_us.begin()->second;
  const std::int64_t last_publish = steady_us();
  const std::int64_t absent_armed_us = bridge.absent_us(first_publish, last_publish);
  bridge.wait_chip_time(last_publish, 200.0);  // the "mixer" is gone

  // Every channel's frames, with the wall time of their first rise.
  auto decode = [&](const std::vector<avr::RealtimeBridge::TimedEdge>& edges) {
    std::vector<avr::PinEdge> plain;
    std::map<std::uint64_t, std::int64_t> wall_of;
    for (const auto& e : edges) {
      plain.push_back(e.edge);
      wall_of[e.edge.cycle] = e.wall_us;
    }
    std::vector<std::vector<std::pair<std::int64_t, avr::DshotFrame>>> out(kMotors);
    for (int ch = 0; ch < kMotors; ++ch) {
      avr::DshotEsc esc(ch, kBitCycles);
      esc.feed(plain);
      for (const avr::DshotFrame& f : esc.take_frames())
        out[static_cast<std::size_t>(ch)].push_back({wall_of.at(f.start_cycle), f});
      // The slice of edges may start inside a frame: that one, no other.
      EXPECT_LE(esc.broken(), 1) << "channel " << ch;
    }
    return out;
  };
  const auto frames = decode(bridge.take_edges());
  const std::int64_t late = kReceiveSlackUs + static_cast<std::int64_t>(bridge.max_lag_us());
  int armed_frames = 0, judged_frames = 0, matched = 0, bad = 0;
  std::vector<double> latency_ms;
  for (std::size_t i = 0; i < frames[0].size(); ++i) {
    const auto& [at, f0] = frames[0][i];
    for (int ch = 0; ch < kMotors; ++ch) {
      const auto& fc = frames[static_cast<std::size_t>(ch)];
      bad += fc.size() > i && !fc[i].second.crc_ok ? 1 : 0;
    }
    if (at > last_publish || f0.value == 0) continue;
    ++armed_frames;
    // The newest message published before the frame whose throttles it carries.
    int best = -1;
    const std::int64_t from = carried_from(bridge, at);
    for (const auto& [k, t] : published_us) {
      if (t >= at + late || t < from) continue;
      bool all = true;
      for (int ch = 0; ch < kMotors && all; ++ch) {
        const auto& fc = frames[static_cast<std::size_t>(ch)];
        all = fc.size() > i && fc[i].second.value == expected[k][static_cast<std::size_t>(ch)];
      }
      if (all) best = k;
    }
    if (best < 0) continue;
    ++matched;
    if (!judged(bridge, published_us[best], at)) continue;
    ++judged_frames;
    latency_ms.push_back(static_cast<double>(at - published_us[best]) / 1000.0);
  }
  // Motor stop after the last message: within the output's staleness
  // (50 ms) and a frame, and no throttle after the first stop.
  double stop_ms = NAN;
  bool throttle_after_stop = false;
  for (const auto& [at, f] : frames[0]) {
    if (at <= last_publish) continue;
    if (std::isnan(stop_ms)) {
      if (f.value == 0) stop_ms = static_cast<double>(at - last_publish) / 1000.0;
    } else if (f.value != 0) {
      throttle_after_stop = true;
    }
  }
  std::printf(
      "DShot600 through motormix output: %d armed frames, %d carry a motor_pwm_t of the 10 ms "
      "before, %d bad checksums; bus to frame p50 %.2f ms, p99 %.2f ms (%d frames judged: the chip "
      "running around them); motor stop %.1f ms after the last motor_pwm_t; chip late by %.2f ms "
      "at worst, absent %.0f ms of the %.0f ms armed; the simulation took %.2f s a simulated "
      "second\n",
      armed_frames, matched, bad, percentile(latency_ms, 0.5), percentile(latency_ms, 0.99),
      judged_frames, stop_ms, bridge.max_lag_us() / 1000.0,
      static_cast<double>(absent_armed_us) / 1000.0,
      static_cast<double>(last_publish - first_publish) / 1000.0, bridge.cost());
  EXPECT_EQ(bad, 0);
  // A frame each kFrameMs the chip ran.
  const double ran_ms =
      static_cast<double>(last_publish - first_publish - absent_armed_us) / 1000.0;
  EXPECT_GT(armed_frames, static_cast<int>(ran_ms / kFrameMs * 0.9));
  EXPECT_GE(matched, armed_frames * kMatchedShare);
  ASSERT_GE(judged_frames, kMinJudged) << kTooBusy;
  EXPECT_LE(percentile(latency_ms, 0.5), kFrameMs + 1.0 + 1.0);
  EXPECT_LE(stop_ms, kMixerDeathBoundMs + absent_ms(bridge, last_publish, stop_ms));
  EXPECT_FALSE(throttle_after_stop);

  // Armed again, then the output SIGKILLed: the chip stops the motors.
  for (int k = 0; k < 200; ++k) {
    motormix::motor_pwm_t m{};
    m.num_motors = kMotors;
    m.pwm.assign(kMotors, 1600.0f);
    m.command.assign(kMotors, 0.6f);
    m.direction.assign(kMotors, 0);
    m.armed = true;
    lcm.publish("MOTOR_PWM", &m);
    std::this_thread::sleep_for(std::chrono::microseconds(2500));
    if (k == 150) output->signal(SIGKILL);
  }
  const std::int64_t killed = steady_us() - 49 * 2500;
  bridge.wait_chip_time(killed, 200.0);
  const auto after = decode(bridge.take_edges());
  double killed_stop_ms = NAN;
  bool armed_before_kill = false;
  for (const auto& [at, f] : after[0]) {
    if (at <= killed) {
      armed_before_kill |= f.value == throttle(1600.0f);
      continue;
    }
    if (f.value == 0) {
      killed_stop_ms = static_cast<double>(at - killed) / 1000.0;
      break;
    }
  }
  std::printf("motor stop %.1f ms after SIGKILL of motormix output\n", killed_stop_ms);
  EXPECT_TRUE(armed_before_kill);
  EXPECT_LE(killed_stop_ms, kOutputDeathBoundMs + absent_ms(bridge, killed, killed_stop_ms));
  EXPECT_GT(killed_stop_ms, 0.0);
  expect_receiver_kept_up(bridge);
  std::remove(config.c_str());
}

// The mixer's motor_pwm_t as the test receives it, with when.
class PwmRecorder {
 public:
  PwmRecorder(lcm::LCM& lcm, const std::string& channel) : lcm_(lcm) {
    // LCM keeps 30 messages per subscription and drops the newest beyond
    // them: a recorder thread that runs late on a loaded machine would lose
    // messages, and their periods would look unmatched.
    lcm_.subscribe(channel, &PwmRecorder::on, this)->setQueueCapacity(100000);
    thread_ = std::thread([this] {
      while (!stop_) lcm_.handleTimeout(20);
    });
  }
  ~PwmRecorder() {
    stop_ = true;
    thread_.join();
  }
  struct Record {
    std::int64_t at_us;
    bool armed;
    std::vector<float> pwm;
  };
  std::vector<Record> records() {
    std::lock_guard<std::mutex> lock(mutex_);
    return records_;
  }

 private:
  void on(const lcm::ReceiveBuffer*, const std::string&, const motormix::motor_pwm_t* m) {
    // When the mixer published it (its utime, this host's wall clock), on
    // the steady clock. Not when this recorder received it: on a loaded
    // two-core machine beside the simulated chip, the recorder's receive
    // thread ran late by more than the slack while the output process had
    // long acted on the message (1-3 % of periods unmatched, with the same
    // binaries that matched 99.7-100 % on a quieter run).
    const std::int64_t wall_now = std::chrono::duration_cast<std::chrono::microseconds>(
                                      std::chrono::system_clock::now().time_since_epoch())
                                      .count();
    const std::int64_t at = m->utime - (wall_now - steady_us());
    std::lock_guard<std::mutex> lock(mutex_);
    records_.push_back({at, m->armed != 0, m->pwm});
  }
  lcm::LCM& lcm_;
  std::mutex mutex_;
  std::vector<Record> records_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// The bundled team-quad flight through the real mixer and the output
// process: each armed period's pulses are the values of a motor_pwm_t the
// mixer published just before its rise; then the mixer is SIGKILLed.
TEST(OutputEndToEnd, TheTeamQuadFlightThroughMixerOutputAndFirmware) {
  avr::RealtimeBridge bridge(MOTORMIX_FIRMWARE_ELF);
  const std::string config = source_path("config/team_quad.yaml");
  const std::vector<std::string> hw = {"--set", "hardware.driver=serial", "--set",
                                       "hardware.serial.device=" + bridge.device()};
  std::vector<std::string> output_argv = {motormix_binary(), "output", "--config", config};
  output_argv.insert(output_argv.end(), hw.begin(), hw.end());
  ChildProcess output(output_argv, "/tmp/motormix-e2e-output2.log");
  ChildProcess mixer({motormix_binary(), "run", "--config", config}, "/tmp/motormix-e2e-run.log");
  lcm::LCM lcm;
  ASSERT_TRUE(lcm.good());
  PwmRecorder recorder(lcm, "motor_pwm");  // the team's channel names (config/team_quad.yaml)
  std::this_thread::sleep_for(std::chrono::milliseconds(600));
  bridge.take_pulses();
  bridge.reset_max_lag();
  ChildProcess player({"lcm-logplayer", source_path("test/data/flights/team_quad.lcmlog")});
  std::this_thread::sleep_for(std::chrono::seconds(6));  // into the armed flight
  mixer.signal(SIGKILL);
  const std::int64_t killed = steady_us();
  bridge.wait_chip_time(killed, 300.0);
  player.signal(SIGKILL);
  const std::vector<Period> periods = periods_of(bridge.take_pulses());
  const std::vector<PwmRecorder::Record> pwm = recorder.records();

  int armed_periods = 0, judged_periods = 0, matched = 0;
  double worst = 0.0;
  // The simulated chip runs behind real time by up to max_lag_us: a rise at
  // simulated time t saw the bytes written until t plus the lag.
  const std::int64_t late = kReceiveSlackUs + static_cast<std::int64_t>(bridge.max_lag_us());
  for (const Period& p : periods) {
    if (p.rise_us > killed || disarmed(p)) continue;
    ++armed_periods;
    judged_periods += judged(bridge, p.rise_us - kCarriedWithinUs, p.rise_us) ? 1 : 0;
    const std::int64_t from = carried_from(bridge, p.rise_us);
    // The best match among the armed messages published in the 10 ms
    // before the rise.
    double best = 1e9;
    for (const auto& r : pwm) {
      if (!r.armed || r.at_us >= p.rise_us + late || r.at_us < from) continue;
      double e = 0.0;
      for (int ch = 0; ch < 4; ++ch)
        e = std::max(e, std::abs(p.width.at(ch) - r.pwm[static_cast<std::size_t>(ch)]));
      best = std::min(best, e);
    }
    if (best <= kPulseToleranceUs) ++matched;
    if (best < 1e9) worst = std::max(worst, best);
  }
  const double gone_ms = ms_to_disarmed(periods, killed);
  const double held_ms = longest_stall_ms(
      periods, killed, [&](const Period& held, std::int64_t from, std::int64_t to) -> std::int64_t {
        for (const auto& r : pwm) {
          if (r.armed && r.at_us > from && r.at_us < to && differs(held, r.pwm)) return r.at_us;
        }
        return -1;
      });
  std::printf(
      "team quad flight: %d armed periods (%d with the chip running in the 10 ms before), %d "
      "match a motor_pwm_t of the 10 ms before within %.1f us (worst %.3f us); held at most "
      "%.2f ms; disarmed %.1f ms after SIGKILL of motormix run; simulation late by %.2f ms at "
      "worst\n",
      armed_periods, judged_periods, matched, kPulseToleranceUs, worst, held_ms, gone_ms,
      bridge.max_lag_us() / 1000.0);
  EXPECT_LE(held_ms, kHeldPeriods * kPeriodMs + kHeldSlackMs + bridge.max_lag_us() / 1000.0);
  EXPECT_GT(gone_ms, 0.0) << "armed again after disarming, or never disarmed";
  // A period each 2.5 ms the chip ran, from the mixer's first armed message.
  std::int64_t first_armed = killed;
  for (const auto& r : pwm)
    if (r.armed) first_armed = std::min(first_armed, r.at_us);
  const double ran_ms =
      static_cast<double>(killed - first_armed - bridge.absent_us(first_armed, killed)) / 1000.0;
  EXPECT_GT(ran_ms, 3000.0) << "several seconds armed";
  EXPECT_GT(armed_periods, static_cast<int>(ran_ms / kFlightPeriodMs * 0.9));
  EXPECT_GE(matched, armed_periods * kMatchedShare);
  EXPECT_LE(gone_ms, kMixerDeathBoundMs + absent_ms(bridge, killed, gone_ms));
  expect_receiver_kept_up(bridge);
}

// Bring-up through the output (issue 49): the mixer's motor test reaches
// one pin, the others stay disarmed; a test beyond the guards is refused
// and moves nothing, and so is a calibration while a mixer runs; the ESC
// calibration's maximum and minimum reach every pin, then disarmed.
// `motormix esc-calibrate` with its Enter typed after `enter_after_s`.
std::vector<std::string> esc_calibrate(const std::string& config, const char* enter_after_s) {
  return {"/bin/sh", "-c",
          std::string("(sleep ") + enter_after_s + "; echo) | '" + motormix_binary() +
              "' esc-calibrate --config '" + config + "' --props-off --min-seconds 1"};
}

// Periods a second of bring-up must show at least (400 at 400 Hz).
constexpr int kBringupPeriodsMin = 240;

// Periods at 400 Hz the chip could not make since `from_us`: the time it
// was absent (realtime_bridge.hpp).
int periods_absent(avr::RealtimeBridge& bridge, std::int64_t from_us) {
  return static_cast<int>(bridge.absent_us(from_us, steady_us()) / 2500);
}

TEST(OutputEndToEnd, TheMotorTestAndTheEscCalibrationReachThePinsThroughTheOutput) {
  avr::RealtimeBridge bridge(MOTORMIX_FIRMWARE_ELF);
  const std::string config = "/tmp/motormix-e2e-bringup-" + std::to_string(::getpid()) + ".yaml";
  constexpr double kStoppedUs = 950.0;  // disarmed, apart from the armed minimum (1000)
  std::ofstream(config) << "name: e2e-bringup\n"
                           "geometry: {preset: quad_x}\n"
                           "output: {min: 1000, max: 2000, disarmed: 950}\n"
                           "motor_test: {max_throttle: 0.15, max_seconds: 3}\n"
                           "hardware:\n"
                           "  driver: serial\n"
                           "  pulse_rate_hz: 400\n"
                           "  serial: {device: "
                        << bridge.device() << "}\n";
  ChildProcess output({motormix_binary(), "output", "--config", config},
                      "/tmp/motormix-e2e-bringup-output.log");
  auto mixer = std::make_unique<ChildProcess>(
      std::vector<std::string>{motormix_binary(), "run", "--config", config},
      "/tmp/motormix-e2e-bringup-run.log");
  std::this_thread::sleep_for(std::chrono::milliseconds(800));
  bridge.take_pulses();
  const auto near = [](double a, double b) { return std::abs(a - b) <= kPulseToleranceUs; };
  // Widths seen per channel in a stretch of periods: how many periods had
  // channel `ch` at `width`, and how many had any other channel off kStoppedUs.
  struct Seen {
    int at = 0, others_moved = 0, periods = 0;
  };
  const auto seen = [&](const std::vector<Period>& periods, int ch, double width) {
    Seen s;
    for (const Period& p : periods) {
      ++s.periods;
      for (const auto& [c, w] : p.width) {
        if (c == ch && near(w, width)) ++s.at;
        if (c != ch && !near(w, kStoppedUs)) ++s.others_moved;
      }
    }
    return s;
  };

  // Motor 2 at 10 %: 1100 us on its pin for about a second.
  const std::int64_t test_from = steady_us();
  ChildProcess test({motormix_binary(), "motor-test", "--config", config, "--motor", "2",
                     "--throttle", "0.1", "--seconds", "1"},
                    "/tmp/motormix-e2e-bringup-test.log");
  EXPECT_EQ(test.wait_for(std::chrono::seconds(8)), 0);  // once the mixer has started it
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  const Seen spun = seen(periods_of(bridge.take_pulses()), 1, 1100.0);
  std::printf(
      "motor test through the output: %d of %d periods with motor 2 at 1100 us, "
      "%d with another channel off its disarmed pulse\n",
      spun.at, spun.periods, spun.others_moved);
  // 1 s at 400 Hz; measured 280-320 periods (the request's way through the
  // bus and the mixer, the chip's pace against the wall clock), less the
  // periods of the time the chip was absent.
  EXPECT_GE(spun.at, kBringupPeriodsMin - periods_absent(bridge, test_from));
  EXPECT_EQ(spun.others_moved, 0);

  // Beyond the guard (motor_test.max_throttle 0.15): refused, nothing moves.
  ChildProcess refused({motormix_binary(), "motor-test", "--config", config, "--motor", "3",
                        "--throttle", "0.5", "--seconds", "1"},
                       "/tmp/motormix-e2e-bringup-refused.log");
  const std::optional<int> refused_exit = refused.wait_for(std::chrono::seconds(8));
  ASSERT_TRUE(refused_exit.has_value());
  EXPECT_NE(*refused_exit, 0);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const Seen still = seen(periods_of(bridge.take_pulses()), 2, kStoppedUs);
  EXPECT_EQ(still.others_moved, 0);
  EXPECT_EQ(still.at, still.periods) << "motor 3 moved on a refused test";

  // The ESC calibration while a mixer runs: refused as it listens, nothing
  // moves.
  ChildProcess busy(esc_calibrate(config, "5"), "/tmp/motormix-e2e-bringup-busy.log");
  const std::optional<int> busy_exit = busy.wait_for(std::chrono::seconds(8));
  ASSERT_TRUE(busy_exit.has_value());
  EXPECT_NE(*busy_exit, 0);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const Seen quiet = seen(periods_of(bridge.take_pulses()), 0, kStoppedUs);
  EXPECT_EQ(quiet.others_moved, 0);
  EXPECT_EQ(quiet.at, quiet.periods) << "a pin moved on a refused calibration";

  // The ESC calibration, with no mixer on the bus: maximum on every pin,
  // Enter, minimum, disarmed.
  mixer->signal(SIGTERM);
  EXPECT_EQ(mixer->wait_for(std::chrono::seconds(3)), 0);
  mixer.reset();
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));  // the mixer's last words are old
  bridge.take_pulses();
  const std::int64_t calibrate_from = steady_us();
  ChildProcess calibrate(esc_calibrate(config, "2.5"), "/tmp/motormix-e2e-bringup-calibrate.log");
  EXPECT_EQ(calibrate.wait_for(std::chrono::seconds(15)), 0);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  int at_max = 0, at_min = 0, after = 0, stopped_after = 0;
  bool min_seen = false;
  for (const Period& p : periods_of(bridge.take_pulses())) {
    const bool all_max = std::all_of(p.width.begin(), p.width.end(),
                                     [&](const auto& w) { return near(w.second, 2000.0); });
    const bool all_min = std::all_of(p.width.begin(), p.width.end(),
                                     [&](const auto& w) { return near(w.second, 1000.0); });
    const bool all_stopped = std::all_of(p.width.begin(), p.width.end(),
                                         [&](const auto& w) { return near(w.second, kStoppedUs); });
    at_max += all_max && !min_seen ? 1 : 0;
    if (all_min) {
      min_seen = true;
      ++at_min;
    } else if (min_seen) {
      ++after;
      stopped_after += all_stopped ? 1 : 0;
    }
  }
  std::printf(
      "ESC calibration through the output: %d periods at the maximum, %d at the minimum, "
      "%d after (%d disarmed)\n",
      at_max, at_min, after, stopped_after);
  // About 1.5 s at the maximum (measured 597) and --min-seconds 1 (measured
  // 299-300), less what the chip could not make.
  const int lost = periods_absent(bridge, calibrate_from);
  EXPECT_GE(at_max, kBringupPeriodsMin - lost);
  EXPECT_GE(at_min, kBringupPeriodsMin - lost);
  EXPECT_GT(after, 0);
  EXPECT_EQ(stopped_after, after);
  output.signal(SIGTERM);
  EXPECT_EQ(output.wait_for(std::chrono::seconds(3)), 0);
  std::remove(config.c_str());
}

}  // namespace
}  // namespace motormix::test
