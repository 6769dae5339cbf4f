#pragma once
// The two clocks every motormix process reads, defined once.
//
// The wall clock (CLOCK_REALTIME, microseconds since the Unix epoch) stamps
// every message a process publishes and is what its input checks compare
// utimes with ("from the future", the signature's skew). The monotonic clock
// (CLOCK_MONOTONIC) times everything else: loop periods, staleness, the
// output gate, timeouts; it never steps when an operator or NTP sets the time.

#include <chrono>
#include <cstdint>
#include <ctime>

namespace motormix::bus {

inline std::int64_t wall_us() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000 + ts.tv_nsec / 1000;
}

inline std::int64_t monotonic_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

inline std::int64_t monotonic_us() { return monotonic_ns() / 1000; }

inline double monotonic_s() { return static_cast<double>(monotonic_ns()) * 1e-9; }

// The monotonic clock as a std::chrono clock, for waits and deadlines
// written with durations (libstdc++ reads CLOCK_MONOTONIC for it).
using MonotonicClock = std::chrono::steady_clock;

}  // namespace motormix::bus
