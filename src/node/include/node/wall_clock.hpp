#pragma once
// This host's wall clock in microseconds since the Unix epoch: the utime of
// every message a motormix process publishes, and the clock its input checks
// compare utimes with (messages "from the future").

#include <cstdint>
#include <ctime>

namespace motormix::node {

inline std::int64_t wall_us() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000 + ts.tv_nsec / 1000;
}

}  // namespace motormix::node
