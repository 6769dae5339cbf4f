#pragma once
// The `realtime:` settings of `motormix run` and `motormix output` (SCHED_FIFO priority, CPU
// affinity, locked and prefaulted memory), applied as requests: what the
// system refuses is logged and the loop runs on without it. What was
// actually granted is read back from the kernel, logged, and reported in
// the timing report, so that a measurement says what it ran under.

#include <motormix/config/config.hpp>

#include <iosfwd>
#include <string>
#include <vector>

namespace motormix::realtime {

struct RealtimeGranted {
  std::string policy;     // "SCHED_FIFO", "SCHED_OTHER", ... as the kernel reports it
  int priority = 0;       // its static priority (0 outside the real-time policies)
  std::vector<int> cpus;  // the CPUs the thread may run on
  bool memory_locked = false;
  bool stack_prefaulted = false;
  // The process's other threads (LCM's receive thread, the drops reader),
  // moved off the loop's CPUs when `cpus` leaves some free.
  int other_threads = 0;
  std::vector<int> other_cpus;
};

// Applies `rt` to the calling thread (the loop), logging each refusal on
// `log`, and returns what is in force. Call it after every other thread has
// started: those keep the default scheduler (a thread started later would
// inherit SCHED_FIFO and share the loop's priority), and with `cpus` set
// they are moved to the CPUs the loop does not use, so that LCM's receive
// thread, which wakes for every message on the bus (the mixer's own outputs
// included), never runs on the loop's CPU.
RealtimeGranted apply_realtime(const config::Realtime& rt, std::ostream& log);

// One line: "SCHED_FIFO 80, cpus 1, memory locked, stack prefaulted".
std::string describe(const RealtimeGranted& granted);

}  // namespace motormix::realtime
