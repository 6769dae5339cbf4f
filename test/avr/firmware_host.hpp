#pragma once
// The host's side of the link for the firmware's tests (test/avr): the
// simulated board, the session learnt from the chip's reports, frames to
// send, and what comes back.

#include "avr_board.hpp"
#include "motormix_link.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <vector>

#ifndef MOTORMIX_FIRMWARE_ELF
#error "MOTORMIX_FIRMWARE_ELF: the firmware under test"
#endif

namespace motormix::avr {

// The bound for a pulse against the width asked for.
constexpr double kPulseToleranceUs = 1.0;
constexpr double kLinkTimeoutMs = 100.0;
// The longest a received byte may wait unread: two and a half byte times
// at 250000 baud, when the next start bit can find the receiver full.
constexpr double kLongestUnreadUs = 100.0;

class Host {
 public:
  // Past the C start-up and the first report, which names the session.
  Host() : board(MOTORMIX_FIRMWARE_ELF) { learn_session(); }
  // Every test's traffic at the chip's receive depth: a byte the chip's
  // receiver could not have held fails the test it came in.
  ~Host() {
    std::printf("receiver: longest unread %.1f us, overruns %d (depth %d)\n",
                board.longest_unread_us(), board.overruns(), AvrBoard::kReceiveDepth);
    EXPECT_EQ(board.overruns(), 0) << "bytes a real ATmega328P's receiver would have lost";
    EXPECT_LT(board.longest_unread_us(), kLongestUnreadUs);
  }

  // Runs until a report names a session other than the one known (bounded),
  // as a host does: frames go for the chip's current session.
  void learn_session() {
    const std::uint32_t before = session;
    for (int i = 0; i < 200 && session == before; ++i) {
      board.run_for_us(1000);
      last_report();
      session = report.session;
    }
    seq = report.last_sequence + 1;
  }

  mm_link_config config(std::uint8_t count = 4, std::uint16_t period_us = 2500,
                        std::uint16_t disarmed = 1000,
                        std::uint8_t protocol = MM_LINK_PROTOCOL_PWM) {
    mm_link_config c{};
    c.protocol = protocol;
    c.period_us = period_us;
    c.link_timeout_ms = static_cast<std::uint16_t>(kLinkTimeoutMs);
    c.min_us = 1000;
    c.max_us = 2000;
    c.count = count;
    for (int i = 0; i < count; ++i) c.disarmed_us[i] = disarmed;
    return c;
  }
  void send_config(const mm_link_config& c) {
    mm_link_config copy = c;
    copy.session = session;
    copy.sequence = seq++;
    std::uint8_t buf[MM_LINK_MAX_FRAME];
    const std::size_t n = mm_link_encode_config(&copy, buf);
    ASSERT_GT(n, 0u);
    board.send(buf, n);
  }
  // ask: the channel whose ESC the frame asks for its KISS telemetry (-1: none).
  std::vector<std::uint8_t> pulses_frame(const std::vector<double>& widths, bool armed,
                                         int ask = -1) {
    mm_link_pulses p{};
    p.telemetry = static_cast<std::uint8_t>(ask + 1);
    p.session = session;
    p.sequence = seq++;
    p.armed = static_cast<std::uint8_t>(armed ? (1u << widths.size()) - 1u : 0u);
    p.count = static_cast<std::uint8_t>(widths.size());
    for (std::size_t i = 0; i < widths.size(); ++i)
      p.pulse_hus[i] = static_cast<std::uint16_t>(std::lround(2.0 * widths[i]));
    std::vector<std::uint8_t> buf(MM_LINK_MAX_FRAME);
    buf.resize(mm_link_encode_pulses(&p, buf.data()));
    return buf;
  }
  void send_pulses(const std::vector<double>& widths, bool armed = true, int ask = -1) {
    board.send(pulses_frame(widths, armed, ask));
  }
  void send_command(std::uint8_t command, std::uint8_t channels, std::uint8_t repeat) {
    mm_link_command c{};
    c.session = session;
    c.sequence = seq++;
    c.command = command;
    c.channels = channels;
    c.repeat = repeat;
    std::uint8_t buf[MM_LINK_MAX_FRAME];
    const std::size_t n = mm_link_encode_command(&c, buf);
    ASSERT_GT(n, 0u);
    board.send(buf, n);
  }
  // The last report the firmware sent (it sends one every 50 ms); the
  // TELEMETRY frames that came meanwhile are kept in `telemetry`.
  mm_link_report last_report() {
    for (std::uint8_t b : board.take_output()) {
      mm_link_frame f{};
      const std::uint8_t type = mm_link_feed(&parser, b, &f);
      if (type == MM_LINK_REPORT) {
        report = f.u.report;
        ++reports;
      } else if (type == MM_LINK_TELEMETRY) {
        telemetry.push_back(f.u.telemetry);
      }
    }
    return report;
  }
  // Runs until everything sent is in, then takes the pulses since: how many
  // of them are off `widths` by more than the bound (each printed), and
  // adds their number to `pulses`. `what` and `k` name the frame just sent.
  int drain_and_count_changed(const std::vector<double>& widths, int& pulses, const char* what,
                              int k) {
    while (board.sending()) board.run_for_us(200);
    int changed = 0;
    for (const Pulse& p : board.take_pulses()) {
      ++pulses;
      if (std::abs(p.width_us - widths[static_cast<std::size_t>(p.channel)]) > kPulseToleranceUs) {
        ++changed;
        std::printf("after %s frame %d: channel %d pulse %.3f us\n", what, k, p.channel,
                    p.width_us);
      }
    }
    return changed;
  }
  // The widths of each channel's last complete pulse.
  static std::map<int, double> last_widths(const std::vector<Pulse>& pulses) {
    std::map<int, double> w;
    for (const Pulse& p : pulses) w[p.channel] = p.width_us;
    return w;
  }

  AvrBoard board;
  std::uint32_t session = 0;
  std::uint32_t seq = 1;
  mm_link_parser parser = [] {
    mm_link_parser p;
    mm_link_parser_init(&p);
    return p;
  }();
  mm_link_report report{};
  int reports = 0;
  std::vector<mm_link_telemetry> telemetry;
};

}  // namespace motormix::avr
