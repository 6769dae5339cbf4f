// Faults around a running `motormix run` on a private bus: the mixer frozen
// and resumed, a publisher frozen and resumed (lcm-logplayer under SIGSTOP),
// duplicated, reordered and delayed messages, publisher clocks that jump,
// floods of undecodable and oversized messages, and no multicast route at
// start-up. In every case: outputs finite and in range, the failsafe right,
// counters that match what was injected, a disarmed last message on exit.

#include "integration/mixer_fixture.hpp"
#include "integration/udp_drops.hpp"

#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <random>
#include <thread>

namespace motormix::test {
namespace {

class Faults : public MixerProcessTest {
 protected:
  // Waits until no more outputs arrive from a frozen mixer (in flight ones landed).
  std::size_t settled_count() {
    std::size_t n = bus_->pwm_count();
    for (int k = 0; k < 50; ++k) {
      std::this_thread::sleep_for(10ms);
      const std::size_t now = bus_->pwm_count();
      if (now == n) return n;
      n = now;
    }
    return n;
  }
};

// The pilot dies while the mixer is frozen. On waking, what waited in the
// socket is as old as it is: the first output after the freeze is already
// the failsafe, not another timeout of armed outputs.
TEST_F(Faults, MixerFrozenWakesWithStaleInputsAndFailsSafeAtOnce) {
  start();
  arm();
  mixer_->signal(SIGSTOP);
  const std::size_t frozen_at = settled_count();
  for (int k = 0; k < 10; ++k) {  // 50 ms more of a live pilot, then nothing
    pilot_->send(true, 0.5);
    std::this_thread::sleep_for(5ms);
  }
  std::this_thread::sleep_for(400ms);
  mixer_->signal(SIGCONT);
  ASSERT_TRUE(bus_->wait_until(
      [&](const auto& pwm, const auto&) { return pwm.size() > frozen_at + 5; }, 5s));
  const auto pwm = bus_->pwm();
  for (std::size_t i = frozen_at; i < pwm.size(); ++i) {
    ASSERT_FALSE(pwm[i].armed) << "output " << i - frozen_at << " after waking was armed";
  }
  ASSERT_TRUE(bus_->wait_until(
      [](const auto&, const auto& s) {
        return !s.empty() && s.back().state == mixer_status_t::STATE_FAILSAFE &&
               s.back().overruns >= 100;  // ~0.45 s of missed periods at 400 Hz, counted
      },
      5s));
  expect_outputs_in_range();
  stop_and_expect_disarmed_exit();
}

// The pilot flies on while the mixer is frozen. A freeze shorter than the
// input timeout goes unnoticed. A longer one is a failsafe (reason: loop
// stalled) even though the pilot is alive: for that long nobody watched the
// inputs, and a downstream ESC bridge will have timed out too. Re-arming
// works as usual. How long a freeze lasts is up to how fast the machine
// stops and resumes the process, so the rule is checked against the gap the
// mixer itself measured: with a status every cycle, the first one after the
// freeze reports it as its period.
TEST_F(Faults, MixerFrozenWhileThePilotFliesOn) {
  start({"status_rate_hz=400"});
  arm();
  ASSERT_TRUE(bus_->wait_until([](const auto&, const auto& s) { return !s.empty(); }, 2s));
  std::int64_t events_before = bus_->status().back().failsafe_events;
  const auto freeze = [&](std::chrono::milliseconds how_long) {
    mixer_->signal(SIGSTOP);
    const std::size_t frozen_at = settled_count();
    const auto until = Clock::now() + how_long;
    for (int k = 0; k < 1000 && Clock::now() < until; ++k) {  // the pilot at 200 Hz
      pilot_->send(true, 0.5);
      std::this_thread::sleep_for(5ms);
    }
    mixer_->signal(SIGCONT);
    return frozen_at;
  };

  const std::size_t statuses_before = bus_->status().size();
  const std::size_t short_freeze = freeze(40ms);
  ASSERT_TRUE(bus_->wait_until(
      [&](const auto&, const auto& s) { return s.size() > statuses_before + 3; }, 2s));
  const auto status = bus_->status();
  const auto resumed = std::max_element(
      status.begin() + static_cast<std::ptrdiff_t>(statuses_before), status.end(),
      [](const auto& a, const auto& b) { return a.period_us[2] < b.period_us[2]; });
  const double gap_ms = resumed->period_us[2] / 1e3;
  const double timeout_ms =
      std::min(config_.inputs.setpoint_timeout_s, config_.inputs.pid_timeout_s) * 1e3;
  SCOPED_TRACE("the mixer was frozen for " + std::to_string(gap_ms) + " ms");
  if (gap_ms <= timeout_ms - kAgeRoundingMs) {
    EXPECT_EQ(resumed->state, mixer_status_t::STATE_ARMED);
    ASSERT_TRUE(fly_until(true, 0.5, [](const motor_pwm_t& m) { return m.armed; }));
    const auto pwm = bus_->pwm();
    for (std::size_t i = short_freeze; i < pwm.size(); ++i) EXPECT_TRUE(pwm[i].armed);
    EXPECT_EQ(bus_->status().back().failsafe_events, events_before);
  } else if (gap_ms > timeout_ms + kAgeRoundingMs) {
    // This machine took longer than the timeout to stop and resume it.
    EXPECT_EQ(resumed->state, mixer_status_t::STATE_FAILSAFE);
    EXPECT_EQ(resumed->failsafe_reason, mixer_status_t::REASON_LOOP_STALLED);
    arm();
    events_before = bus_->status().back().failsafe_events;
  }

  const std::size_t long_freeze = freeze(300ms);
  ASSERT_TRUE(bus_->wait_until(
      [&](const auto& p, const auto& s) {
        return p.size() > long_freeze + 5 && !s.empty() &&
               s.back().failsafe_reason == mixer_status_t::REASON_LOOP_STALLED;
      },
      5s));
  const auto pwm = bus_->pwm();
  for (std::size_t i = long_freeze; i < pwm.size(); ++i) {
    ASSERT_FALSE(pwm[i].armed) << "output " << i - long_freeze << " after a long freeze was armed";
  }
  EXPECT_EQ(bus_->status().back().failsafe_events, events_before + 1);
  arm();
  expect_outputs_in_range();
  stop_and_expect_disarmed_exit();
}

// A publisher process frozen mid-flight and resumed: lcm-logplayer plays the
// team quad flight; frozen for 300 ms, the mixer fails safe in the first
// cycle past its timeout (its own clock, a status every cycle), and when the
// player resumes (still saying "armed") the motors stay disarmed: no restart
// without a new arming transition.
TEST_F(Faults, PublisherFrozenAndResumedFailsSafeAndStaysDisarmed) {
  start({"status_rate_hz=400"});
  ChildProcess player({"lcm-logplayer", source_path("test/data/flights/team_quad.lcmlog")});
  ASSERT_TRUE(bus_->wait_until(
      [](const auto& pwm, const auto&) {
        int armed = 0;
        for (const auto& m : pwm) armed += m.armed;
        return armed > 800;  // two seconds into the armed flight
      },
      15s));
  const std::size_t from = bus_->status().size();
  player.signal(SIGSTOP);
  ASSERT_TRUE(wait_for_failsafe_status(from));
  const std::vector<CycleRecord> cycles = cycles_since(from);
  const auto failsafe = expect_failsafe_in_first_late_cycle(cycles);
  ASSERT_TRUE(failsafe.has_value());
  EXPECT_FALSE(cycles[*failsafe].pwm.armed);
  const std::size_t first = cycles[*failsafe].pwm_index;
  std::this_thread::sleep_for(300ms);
  player.signal(SIGCONT);
  ASSERT_TRUE(player.wait_for(30s).has_value());
  const auto pwm = bus_->pwm();
  for (std::size_t i = first; i < pwm.size(); ++i) ASSERT_FALSE(pwm[i].armed);
  ASSERT_TRUE(bus_->wait_until([](const auto&, const auto& s) { return !s.empty(); }, 2s));
  EXPECT_EQ(bus_->status().back().failsafe_events, 1);
  expect_outputs_in_range();
  stop_and_expect_disarmed_exit();
}

// A burst: lcm-logplayer plays the 14 s flight at 50 times its speed (about
// 25 000 messages a second). Nothing is rejected, and every message of the log
// is accepted except those the kernel dropped before motormix could read them
// (a full socket receive buffer on a loaded machine, counted in RcvbufErrors):
// motormix runs with the larger buffer the README recommends for bursts, and
// any message missing beyond the kernel's count is motormix's loss, a failure.
// The outputs stay in range.
TEST_F(Faults, BurstAtFiftyTimesSpeedLosesNothing) {
  start({}, "config/team_quad.yaml",
        {"--lcm-url", "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=2097152"});
  int setpoints = 0, pids = 0;
  {
    lcm::LogFile log(source_path("test/data/flights/team_quad.lcmlog"), "r");
    while (const lcm::LogEvent* ev = log.readNextEvent()) {
      setpoints += ev->channel == config_.channels.setpoint;
      pids += ev->channel == config_.channels.pid;
    }
  }
  const long drops_before = udp_receive_buffer_drops();
  ASSERT_GE(drops_before, 0) << "cannot read Udp RcvbufErrors from /proc/net/snmp";
  ChildProcess player(
      {"lcm-logplayer", "-s", "50", source_path("test/data/flights/team_quad.lcmlog")});
  ASSERT_EQ(player.wait_for(30s), 0);
  // Every message accepted, or (on a loaded machine) until the counts stop
  // growing: 5 s is twenty status periods after the last message.
  bus_->wait_until(
      [&](const auto&, const auto& s) {
        return !s.empty() && s.back().setpoint_received + s.back().pid_received >= setpoints + pids;
      },
      5s);
  const long kernel_drops = udp_receive_buffer_drops() - drops_before;
  const auto status = bus_->status();  // a copy: `last` must not outlive it
  ASSERT_FALSE(status.empty());
  const auto& last = status.back();
  const long missing = (setpoints - last.setpoint_received) + (pids - last.pid_received);
  EXPECT_LE(last.setpoint_received, setpoints);
  EXPECT_LE(last.pid_received, pids);
  // The kernel's count covers every socket on the private bus (the test's
  // own recorder too), so it bounds what motormix could have lost there.
  EXPECT_LE(missing, kernel_drops) << "accepted " << last.setpoint_received << " setpoints of "
                                   << setpoints << ", " << last.pid_received << " pid of " << pids
                                   << "; the kernel dropped " << kernel_drops << " datagrams";
  if (missing > 0 && missing <= kernel_drops) {
    std::printf("note: %ld of %d messages dropped by the kernel (receive buffer full)\n", missing,
                setpoints + pids);
  }
  EXPECT_EQ(last.rejected_decode + last.rejected_range + last.rejected_nonfinite +
                last.rejected_stale_order + last.rejected_future,
            0);
  int armed = 0;
  for (const auto& m : bus_->pwm()) armed += m.armed;
  EXPECT_GT(armed, 0) << "the burst never armed the mixer";
  expect_outputs_in_range();
  stop_and_expect_disarmed_exit();
}

// Duplicates are harmless, messages older than the one in force are counted
// and dropped, and a publisher whose clock jumps ahead is refused until its
// clock is right again (and then the motors need a new arming transition).
TEST_F(Faults, DuplicatesReorderingAndClockJumpsAreCountedAndFailSafe) {
  // 500 ms timeouts: a stall of a loaded machine cannot end the first part's
  // flight, and the refused clock jump still fails safe well within the wait.
  start({"inputs.setpoint_timeout_ms=500", "inputs.pid_timeout_ms=500"});
  arm();
  // Duplicates and reordering: each message twice, then an older one.
  setpoint_t sp{};
  sp.throttle = 0.5F;
  sp.armed = true;
  pid_t pid{};
  constexpr int kReordered = 20;
  for (int k = 0; k < kReordered; ++k) {
    const std::int64_t now = wall_us();
    sp.utime = now;
    pid.utime = now;
    pilot_->message(config_.channels.setpoint, sp);
    pilot_->message(config_.channels.setpoint, sp);
    pilot_->message(config_.channels.pid, pid);
    pid.utime = now - 2000;  // older than the one in force
    pilot_->message(config_.channels.pid, pid);
    std::this_thread::sleep_for(2ms);
  }
  ASSERT_TRUE(bus_->wait_until(
      [](const auto&, const auto& s) {
        return !s.empty() && s.back().rejected_stale_order >= kReordered;
      },
      3s));
  ASSERT_TRUE(fly_until(true, 0.5, [](const motor_pwm_t& m) { return m.armed; }));
  const std::int64_t failsafes = bus_->status().back().failsafe_events;

  // The publisher's clock jumps an hour ahead: refused as from the future.
  constexpr int kFuture = 30;
  for (int k = 0; k < kFuture; ++k) {
    sp.utime = wall_us() + 3'600'000'000LL;
    pilot_->message(config_.channels.setpoint, sp);
    std::this_thread::sleep_for(5ms);
  }
  ASSERT_TRUE(bus_->wait_until(
      [&](const auto&, const auto& s) {
        return !s.empty() && s.back().rejected_future >= kFuture &&
               s.back().state == mixer_status_t::STATE_FAILSAFE &&
               s.back().failsafe_events == failsafes + 1;
      },
      3s));
  // Back to the right time: accepted (a large step back is a restarted
  // publisher), but the motors stay disarmed until re-armed.
  for (int k = 0; k < 20; ++k) {
    ASSERT_TRUE(fly_until(true, 0.5, [](const motor_pwm_t&) { return true; }));
    ASSERT_FALSE(bus_->pwm().back().armed);
  }
  arm();
  expect_outputs_in_range();
  stop_and_expect_disarmed_exit();
}

// A flood while the mixer is frozen fills its socket's receive buffer: the
// kernel drops what no longer fits, and LCM never sees those messages. The
// mixer reports the kernel's count for its own sockets (kernel_drops): 0
// before, more than 0 after, and never more than the namespace lost in all
// (the private bus holds only this test's sockets and the mixer's).
TEST_F(Faults, KernelDropsOnTheMixersOwnSocketAreReported) {
  start({"status_rate_hz=400"});
  arm();
  // Read once a second off the loop thread: -1 until the first reading
  // that finds the mixer's sockets.
  ASSERT_TRUE(bus_->wait_until(
      [](const auto&, const auto& s) { return !s.empty() && s.back().kernel_drops >= 0; }, 5s))
      << "-1 means the mixer could not find its sockets in /proc/net/udp";
  ASSERT_EQ(bus_->status().back().kernel_drops, 0);
  const long namespace_before = udp_receive_buffer_drops();
  ASSERT_GE(namespace_before, 0);
  // The test's own socket on the group, overflowing unread.
  const UnreadMulticastSocket unread;
  ASSERT_TRUE(unread.ok());
  const long unread_before = unread.drops();
  ASSERT_GE(unread_before, 0);
  mixer_->signal(SIGSTOP);
  const std::size_t frozen_at = settled_count();
  // Far more than a default receive buffer (about 200 kB) holds of small
  // datagrams; sent slowly enough that this test's own receivers keep up.
  constexpr int kFlood = 4000;
  for (int k = 0; k < kFlood; ++k) {
    pilot_->send(true, 0.5);
    if (k % 20 == 0) std::this_thread::sleep_for(1ms);
  }
  std::this_thread::sleep_for(100ms);
  mixer_->signal(SIGCONT);
  ASSERT_TRUE(bus_->wait_until(
      [&](const auto& pwm, const auto& s) {
        return pwm.size() > frozen_at + 20 && !s.empty() && s.back().kernel_drops > 0;
      },
      5s))
      << "no kernel drops reported after the flood";
  const std::int64_t reported = bus_->status().back().kernel_drops;
  const long namespace_drops = udp_receive_buffer_drops() - namespace_before;
  const long unread_drops = unread.drops() - unread_before;
  EXPECT_GT(unread_drops, 0) << "the test's own socket should have overflowed";
  EXPECT_GT(reported, 0);
  // What the namespace dropped, less the test's socket: a mixer that summed
  // every socket in /proc/net/udp would report the test's drops too.
  EXPECT_LE(reported, namespace_drops - unread_drops)
      << "namespace " << namespace_drops << ", the test's socket " << unread_drops;
  expect_outputs_in_range();
  stop_and_expect_disarmed_exit();
}

// Floods on both input channels: random bytes, and messages far larger than
// any input, at 2 kHz while the pilot flies. The loop keeps cycling through
// the flood (a drain is bounded per wake-up), every injected message is
// counted, nothing leaves the range.
TEST_F(Faults, FloodsOfUndecodableAndOversizedMessagesAreCounted) {
  start({"status_rate_hz=400"});  // a status every cycle
  arm();
  std::mt19937 rng(1234);
  constexpr int kFlood = 1000;
  ASSERT_TRUE(bus_->wait_until([](const auto&, const auto& s) { return !s.empty(); }, 5s));
  const std::size_t statuses_before = bus_->status().size();
  const std::int64_t failsafes_before = bus_->status().back().failsafe_events;
  for (int k = 0; k < kFlood; ++k) {
    const std::size_t size = k % 10 == 0 ? 60000 : 1 + rng() % 100;  // every tenth: 60 kB
    std::vector<std::uint8_t> junk(size);
    for (auto& b : junk) b = static_cast<std::uint8_t>(rng());
    pilot_->raw(k % 2 ? config_.channels.setpoint : config_.channels.pid, junk);
    if (k % 4 == 0) pilot_->send(true, 0.5);
    std::this_thread::sleep_for(500us);
  }
  ASSERT_TRUE(bus_->wait_until(
      [](const auto&, const auto& s) { return !s.empty() && s.back().rejected_decode >= kFlood; },
      5s))
      << "counted " << bus_->status().back().rejected_decode << " of " << kFlood;
  EXPECT_EQ(bus_->status().back().rejected_decode, kFlood);
  // The loop cycled while the flood came in, not only after it: cycles
  // published with part of it counted. However slow the machine, a wake-up
  // drains at most 1000 messages and the flood and the pilot send 1250.
  const auto status = bus_->status();
  int cycles_within = 0;
  for (std::size_t k = statuses_before; k < status.size(); ++k) {
    const std::int64_t counted = status[k].rejected_decode;
    cycles_within += counted > 0 && counted < kFlood;
  }
  EXPECT_GE(cycles_within, 2);
  ASSERT_TRUE(mixer_->running());
  // On a loaded machine the flood can hold back valid setpoints past their
  // timeout: motormix then fails safe and disarms, as documented, and only a
  // fresh arming sequence flies again. Either way it must fly after the flood.
  const mixer_status_t after = bus_->status().back();
  if (after.failsafe_events > failsafes_before) {
    EXPECT_NE(after.failsafe_reason, mixer_status_t::REASON_INVALID_INPUT)
        << "junk must be rejected, never taken as the inputs in force";
    arm();
  } else {
    ASSERT_TRUE(fly_until(true, 0.5, [](const motor_pwm_t& m) { return m.armed; }));
  }
  expect_outputs_in_range();
  stop_and_expect_disarmed_exit();
}

// Without a multicast route the bus cannot open: one clear message naming the
// fix, exit status 1 within a second, no retry loop.
TEST_F(Faults, NoMulticastRouteIsAClearErrorNotABusyLoop) {
  ASSERT_EQ(std::system("ip route del 224.0.0.0/4 dev lo"), 0);
  const auto t0 = Clock::now();
  const std::string cmd = std::string(motormix_binary()) + " run --config " +
                          source_path("config/team_quad.yaml") + " 2>&1";
  FILE* pipe = popen(cmd.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string out;
  std::array<char, 512> buf{};
  while (fgets(buf.data(), static_cast<int>(buf.size()), pipe)) out += buf.data();
  const int status = pclose(pipe);
  const auto took = Clock::now() - t0;
  EXPECT_EQ(std::system("ip route add 224.0.0.0/4 dev lo"), 0);
  EXPECT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 1);
  EXPECT_LT(took, 5s);
  EXPECT_NE(out.find("ip route add 224.0.0.0/4 dev lo"), std::string::npos) << out;
}

}  // namespace
}  // namespace motormix::test
