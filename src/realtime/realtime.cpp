#include "realtime/realtime.hpp"

#include <dirent.h>
#include <sched.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <ostream>
#include <sstream>

namespace motormix::realtime {

namespace {

// Stack touched once at start-up with memory locked, so that the loop's
// deepest call (the YAML-free per-cycle path is far shallower) never takes a
// page fault on a fresh stack page. 256 KiB is well within the default
// 8 MiB stack.
constexpr std::size_t kStackPrefaultBytes = 256 * 1024;

// noinline: the buffer must be a real frame below the caller's, not folded
// away. volatile writes keep the compiler from dropping the touch.
[[gnu::noinline]] void prefault_stack() {
  volatile unsigned char stack[kStackPrefaultBytes];
  for (std::size_t i = 0; i < sizeof stack; i += 4096) stack[i] = 0;
}

std::string policy_name(int policy) {
  switch (policy) {
    case SCHED_OTHER:
      return "SCHED_OTHER";
    case SCHED_FIFO:
      return "SCHED_FIFO";
    case SCHED_RR:
      return "SCHED_RR";
    case SCHED_BATCH:
      return "SCHED_BATCH";
    case SCHED_IDLE:
      return "SCHED_IDLE";
    default:
      return "policy " + std::to_string(policy);
  }
}

// Every thread of this process but the caller, to the online CPUs outside
// `loop` (none left: they stay where they are).
void move_other_threads(const cpu_set_t& loop, RealtimeGranted& granted) {
  cpu_set_t others;
  CPU_ZERO(&others);
  const long online = sysconf(_SC_NPROCESSORS_ONLN);
  for (int cpu = 0; cpu < online && cpu < CPU_SETSIZE; ++cpu) {
    if (!CPU_ISSET(cpu, &loop)) CPU_SET(cpu, &others);
  }
  if (CPU_COUNT(&others) == 0) return;
  for (int cpu = 0; cpu < online && cpu < CPU_SETSIZE; ++cpu) {
    if (CPU_ISSET(cpu, &others)) granted.other_cpus.push_back(cpu);
  }
  const pid_t self = static_cast<pid_t>(gettid());
  DIR* tasks = opendir("/proc/self/task");
  if (tasks == nullptr) return;
  while (const dirent* entry = readdir(tasks)) {
    if (entry->d_name[0] == '.') continue;
    const pid_t tid = static_cast<pid_t>(std::atoi(entry->d_name));
    if (tid == self || tid <= 0) continue;
    if (sched_setaffinity(tid, sizeof others, &others) == 0) ++granted.other_threads;
  }
  closedir(tasks);
}

}  // namespace

RealtimeGranted apply_realtime(const config::Realtime& rt, std::ostream& log) {
  RealtimeGranted granted;
  if (rt.lock_memory) {
    if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
      log << "motormix: warning: mlockall refused (" << std::strerror(errno) << "); continuing"
          << std::endl;
    } else {
      granted.memory_locked = true;
      prefault_stack();
      granted.stack_prefaulted = true;
    }
  }
  if (!rt.cpus.empty()) {
    cpu_set_t set;
    CPU_ZERO(&set);
    for (int cpu : rt.cpus) CPU_SET(cpu, &set);
    if (sched_setaffinity(0, sizeof set, &set) != 0) {
      log << "motormix: warning: CPU affinity refused (" << std::strerror(errno) << "); continuing"
          << std::endl;
    } else {
      move_other_threads(set, granted);
    }
  }
  if (rt.priority > 0) {
    sched_param param{};
    param.sched_priority = rt.priority;
    if (sched_setscheduler(0, SCHED_FIFO, &param) != 0) {
      log << "motormix: warning: SCHED_FIFO priority " << rt.priority << " refused ("
          << std::strerror(errno) << "); continuing with the default scheduler" << std::endl;
    }
  }
  // What is in force, from the kernel rather than from the requests.
  const int policy = sched_getscheduler(0);
  granted.policy = policy < 0 ? "unknown" : policy_name(policy);
  sched_param param{};
  if (sched_getparam(0, &param) == 0) granted.priority = param.sched_priority;
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) == 0) {
    for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu) {
      if (CPU_ISSET(cpu, &set)) granted.cpus.push_back(cpu);
    }
  }
  return granted;
}

std::string describe(const RealtimeGranted& granted) {
  std::ostringstream s;
  s << granted.policy;
  if (granted.priority > 0) s << " " << granted.priority;
  s << ", cpus";
  for (std::size_t i = 0; i < granted.cpus.size(); ++i) s << (i ? "," : " ") << granted.cpus[i];
  s << (granted.memory_locked ? ", memory locked" : ", memory not locked");
  if (granted.stack_prefaulted) s << ", stack prefaulted";
  if (granted.other_threads > 0) {
    s << ", " << granted.other_threads << " other thread" << (granted.other_threads > 1 ? "s" : "")
      << " moved to cpus";
    for (std::size_t i = 0; i < granted.other_cpus.size(); ++i) {
      s << (i ? "," : " ") << granted.other_cpus[i];
    }
  }
  return s.str();
}

}  // namespace motormix::realtime
