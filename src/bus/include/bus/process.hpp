#pragma once
// What every motormix process on the bus starts with and waits on: its
// shutdown signals (blocked, read as a descriptor), the LCM instance opened
// with one message when it cannot be, one wait over the bus, the signals and
// the process' own descriptors, and one bound on the messages handled per
// wake-up. `run`, `output`, `monitor`, `sim --lcm` and the bring-up clients
// are built on it; what each does between two waits is its own.

#include "bus/shutdown_signals.hpp"

#include <lcm/lcm-cpp.hpp>

#include <bitset>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <ostream>
#include <string>

namespace motormix::bus {

// Per-subscription receive queue: deep enough for bursts from a log player
// running faster than real time, small enough to bound memory.
inline constexpr int kQueueCapacity = 1000;
// Messages handled per wake-up before the process' own work gets its turn
// again, so a flood on the bus cannot starve the outputs.
inline constexpr int kMaxMessagesPerDrain = 1000;

// The bus at `url` (empty: LCM_DEFAULT_URL), or nullptr after one message
// on `log`, for every process alike: "<who>: cannot open LCM at <url>",
// what a multicast bus needs, where to read more. No retry: a supervisor
// decides when to try again.
std::unique_ptr<lcm::LCM> open_bus(const std::string& who, const std::string& url,
                                   std::ostream& log);

// Hands queued messages to their handlers, at most `max`, without waiting;
// how many were handled.
int drain(lcm::LCM& lcm, int max = kMaxMessagesPerDrain);

// The process' own descriptors one wait can watch beside the bus and the
// signals: a timer and a telemetry wire per motor fit with room to spare.
inline constexpr std::size_t kMaxWatched = 32;

// What one wait found ready.
struct Woke {
  bool bus = false;              // messages to drain
  bool signal = false;           // a shutdown signal was taken (signals().last_signal())
  std::bitset<kMaxWatched> own;  // the process' own descriptors, by watch()'s index
  int error = 0;                 // poll's errno, 0 when it did not fail
};

class Process {
 public:
  // Blocks the shutdown signals, then opens the bus; `who` ("motormix
  // run") names the process in its messages. Check good() before use.
  Process(std::string who, const std::string& url, std::ostream& log);
  Process(const Process&) = delete;
  Process& operator=(const Process&) = delete;

  // False when either failed; the reason is already on the log.
  bool good() const { return lcm_ != nullptr; }
  const std::string& who() const { return who_; }
  lcm::LCM& lcm() { return *lcm_; }
  ShutdownSignals& signals() { return signals_; }

  // Adds one of the process' own descriptors to every later wait and
  // returns its index in Woke::own; a negative descriptor is never ready.
  // Throws std::length_error beyond kMaxWatched (a start-up error).
  std::size_t watch(int fd);

  // Waits at most `timeout_ns` (negative: for ever) for the bus, a shutdown
  // signal, or a watched descriptor. The wait is as fine as the kernel's
  // (a serial driver waits for a frame's slot in tens of microseconds). An
  // interrupted wait comes back with nothing ready.
  Woke wait_ns(std::int64_t timeout_ns);
  // The same in milliseconds (-1: for ever).
  Woke wait(int timeout_ms) {
    return wait_ns(timeout_ms < 0 ? -1 : static_cast<std::int64_t>(timeout_ms) * 1'000'000);
  }
  // wait_ns(), then what came on the bus handed to its handlers (drain()):
  // a client's pause between two looks.
  Woke wait_and_drain_ns(std::int64_t timeout_ns) {
    const Woke woke = wait_ns(timeout_ns);
    if (woke.bus) drain(*lcm_);
    return woke;
  }

 private:
  std::string who_;
  ShutdownSignals signals_;
  std::unique_ptr<lcm::LCM> lcm_;
  std::size_t watched_ = 0;
  int watched_fds_[kMaxWatched] = {};
};

}  // namespace motormix::bus
