#pragma once
// The LCM side of `motormix run`: subscriptions, a fixed-rate monotonic timer,
// signal handling and publishing. One thread: poll() over the LCM socket, a
// timerfd and a signalfd. No exception leaves an LCM callback.

#include <motormix/config/config.hpp>

#include <atomic>
#include <iosfwd>
#include <string>

namespace motormix::node {

struct RunOptions {
  std::string lcm_url;  // empty: LCM_DEFAULT_URL, then LCM's default
  // Stop by itself after this many cycles (0: run until a signal). Lets tests
  // and demos bound a run without relying on signals.
  long long max_cycles = 0;
  // When set, the whole run's loop timing (wake-up lateness and period:
  // percentiles, largest and when, overruns, kernel drops, the scheduling
  // granted) is written there as JSON at the end of the run.
  std::string timing_report_path;
  // Cycles driven by a simulator's lockstep_t ticks on channels.lockstep,
  // each at its time, instead of the timer (docs/lockstep.md).
  bool lockstep = false;
  // In lockstep: stop by itself once no tick has come for this long (wall
  // clock; 0: wait for ever). A simulator that dies without a word leaves
  // its mixer waiting, and time stands still for it.
  double lockstep_idle_s = 30.0;
};

// Runs until SIGINT, SIGTERM or SIGHUP (then publishes one disarmed message
// and returns 0), max_cycles or, in lockstep, lockstep_idle_s without a tick
// (the same, returning 0 and 3), or a fatal set-up error (returns 1, message
// on `log`).
int run_node(const config::Config& config, const RunOptions& options, std::ostream& log);

}  // namespace motormix::node
