#include "node/lcm_node.hpp"

#include <nlohmann/json.hpp>
#include "bus/clock.hpp"
#include "bus/policy_or_error.hpp"
#include "bus/process.hpp"
#include "bus/sealed_publisher.hpp"
#include "node.hpp"

#include <motormix/config/build_mixer.hpp>
#include <motormix/config/matrix_export.hpp>
#include <motormix/config/security.hpp>
#include <motormix/signing_policy.hpp>
#include "latency_histogram.hpp"
#include "loop/control_loop.hpp"
#include "messages/messages.hpp"
#include "node/run_log.hpp"
#include "realtime/realtime.hpp"
#include "socket_drops.hpp"
#include "window_stats.hpp"

#include <motormix/mixer_status_t.hpp>
#include <motormix/motor_pwm_t.hpp>
#include <motormix/pid_t.hpp>
#include <motormix/setpoint_t.hpp>

#include <lcm/lcm-cpp.hpp>

#include <sched.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/timerfd.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <optional>
#include <ostream>
#include <utility>
#include <vector>

namespace motormix::node {

namespace {

using bus::monotonic_ns;
using bus::monotonic_us;
using bus::wall_us;

// In lockstep, how often (ms) the idle limit is looked at while no tick
// comes, and the exit status once it is reached.
constexpr int kIdleLookMs = 250;
constexpr int kExitLockstepIdle = 3;

// Owns a file descriptor.
class Fd {
 public:
  explicit Fd(int fd) : fd_(fd) {}
  ~Fd() {
    if (fd_ >= 0) close(fd_);
  }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  int get() const { return fd_; }

 private:
  int fd_;
};

}  // namespace

int run_node(const config::Config& config, const RunOptions& options, std::ostream& log) {
  // The key is read before anything reaches the bus: a key file that is
  // missing or open to others stops the start, as a configuration error.
  std::optional<signing::Policy> policy = bus::policy_or_error(config, "run", log);
  if (!policy) return 1;
  // Signals arrive through a descriptor so shutdown happens in the loop, not
  // in an async handler; the bus opened, or one message and exit status 1.
  bus::Process process("motormix run", options.lcm_url, log);
  if (!process.good()) return 1;
  lcm::LCM& lcm = process.lcm();
  Fd timer_fd(timerfd_create(CLOCK_MONOTONIC, TFD_CLOEXEC));
  if (timer_fd.get() < 0) {
    log << "motormix: cannot create the loop's timer descriptor: " << std::strerror(errno)
        << std::endl;
    return 1;
  }
  const SocketDropsWatcher drops;
  Node node(config, std::move(*policy), lcm, drops, log);
  log_summary(config, node.loop(), options.lcm_url, log);
  node.subscribe();  // starts LCM's receive thread
  if (options.lockstep) {
    node.use_lockstep();
    log << "motormix: lockstep: one cycle per lockstep_t on '" << config.channels.lockstep
        << "', at its time (no timer)" << std::endl;
  }
  // After every other thread has started: they keep the default scheduler,
  // and move off the loop's CPUs (realtime/realtime.hpp).
  const realtime::RealtimeGranted granted = realtime::apply_realtime(config.realtime, log);
  log << "motormix: scheduling: " << realtime::describe(granted) << std::endl;

  const auto period_ns = static_cast<long long>(std::llround(1e9 / config.loop_rate_hz));
  itimerspec spec{};
  spec.it_interval.tv_sec = static_cast<time_t>(period_ns / 1'000'000'000);
  spec.it_interval.tv_nsec = static_cast<long>(period_ns % 1'000'000'000);
  // Absolute ticks from a known start, so that each wake-up's lateness is
  // actual minus scheduled time (what cyclictest measures for a thread).
  const std::int64_t start_ns = monotonic_ns() + period_ns;
  spec.it_value.tv_sec = static_cast<time_t>(start_ns / 1'000'000'000);
  spec.it_value.tv_nsec = static_cast<long>(start_ns % 1'000'000'000);
  if (!options.lockstep &&
      timerfd_settime(timer_fd.get(), TFD_TIMER_ABSTIME, &spec, nullptr) != 0) {
    log << "motormix: cannot start loop timer: " << std::strerror(errno) << std::endl;
    return 1;
  }

  // In lockstep the timer is left out (a negative descriptor is skipped).
  const std::size_t timer = process.watch(options.lockstep ? -1 : timer_fd.get());
  long long cycles = 0;
  std::int64_t ticks = 0;  // timer periods elapsed
  // Lockstep: when the last tick (or the start) came, and how long poll may
  // wait before the idle limit is looked at again.
  std::int64_t last_tick_ns = monotonic_ns();
  const auto idle_ns = static_cast<std::int64_t>(options.lockstep_idle_s * 1e9);
  const int poll_ms = options.lockstep && idle_ns > 0 ? kIdleLookMs : -1;
  // Written once at the end, whichever way the loop ends.
  const auto finish = [&](int code) {
    node.publish_disarmed();
    if (options.lockstep)
      log << "motormix: lockstep: " << cycles << " ticks run, " << node.lockstep_refused()
          << " refused (unverified, undecodable, or not later than the last)" << std::endl;
    if (!options.timing_report_path.empty()) {
      std::ofstream report(options.timing_report_path);
      node.write_timing_report(report, granted, ticks);
      if (!report) {
        log << "motormix: cannot write the timing report " << options.timing_report_path
            << std::endl;
      }
    }
    return code;
  };
  while (true) {
    const bus::Woke woke = process.wait(poll_ms);
    if (woke.error != 0) {
      log << "motormix: poll failed: " << std::strerror(woke.error) << std::endl;
      return finish(1);
    }
    if (woke.signal) {
      log << "motormix: signal " << process.signals().last_signal()
          << ", publishing disarmed outputs and exiting" << std::endl;
      return finish(0);
    }
    const std::int64_t woke_ns = monotonic_ns();
    const std::int64_t woke_us = woke_ns / 1000;
    bool run_cycle = false;
    if (woke.bus) {
      node.drain();
      run_cycle = config.publish == config::PublishMode::kOnInput && node.take_new_pid();
    }
    // Each tick one cycle at its time, after everything sent before it and
    // nothing sent after (the drain stops at a tick).
    for (std::int64_t tick = 0; options.lockstep && node.take_tick(tick); node.drain()) {
      last_tick_ns = woke_ns;
      node.cycle(tick, monotonic_us());
      ++cycles;
      if (options.max_cycles > 0 && cycles >= options.max_cycles) return finish(0);
    }
    if (poll_ms >= 0 && woke_ns - last_tick_ns >= idle_ns) {
      log << "motormix: lockstep: no tick for " << options.lockstep_idle_s
          << " s: the simulator is gone; publishing disarmed outputs and exiting" << std::endl;
      return finish(kExitLockstepIdle);
    }
    if (woke.own[timer]) {
      std::uint64_t expirations = 0;
      if (read(timer_fd.get(), &expirations, sizeof expirations) == sizeof expirations) {
        if (expirations > 1) node.add_overruns(expirations - 1);
        // Late from the first tick not yet served: a loop that missed
        // periods was late by all of them, not just by the newest one.
        const std::int64_t scheduled_ns = start_ns + ticks * period_ns;
        ticks += static_cast<std::int64_t>(expirations);
        node.add_wake_latency(static_cast<double>(woke_ns - scheduled_ns) / 1e3, woke_us);
        // Inputs that arrived together with the tick were drained above (the
        // same poll reported them); draining again would cost a select per
        // cycle for nothing.
        run_cycle = true;
      }
    }
    if (run_cycle) {
      node.cycle(monotonic_us(), woke_us);
      ++cycles;
      if (options.max_cycles > 0 && cycles >= options.max_cycles) return finish(0);
    }
  }
}

}  // namespace motormix::node
