#pragma once
// Datagrams the kernel dropped on this process's own UDP sockets because
// their receive buffer was full: the "drops" column of /proc/net/udp and
// /proc/net/udp6 for the socket inodes among /proc/self/fd. A message lost
// there never reached LCM, so no counter of motormix's could see it;
// mixer_status_t reports this one as kernel_drops. (LCM 1.3.1 also drops
// silently when a subscription's queue is full; that loss is not visible
// from outside LCM.)

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <thread>
#include <vector>

namespace motormix::node {

// Since the sockets were opened; -1 when /proc cannot be read (no procfs,
// or no UDP socket of this process in the tables yet).
std::int64_t own_udp_socket_drops();

// Reads own_udp_socket_drops() once a second on a thread of its own: the kernel takes
// about 0.2 ms to produce /proc/net/udp (measured on a private bus), far too
// long for the loop thread (at 8 kHz it was the p99.9 of the wake-up
// lateness). Start it before the loop thread takes its real-time settings,
// so that it keeps the default scheduler and any CPU.
class SocketDropsWatcher {
 public:
  SocketDropsWatcher();
  ~SocketDropsWatcher();  // stops and joins the thread
  SocketDropsWatcher(const SocketDropsWatcher&) = delete;
  SocketDropsWatcher& operator=(const SocketDropsWatcher&) = delete;

  // The latest reading (-1 before the first, or when unreadable).
  std::int64_t latest() const { return latest_.load(std::memory_order_relaxed); }

 private:
  std::atomic<std::int64_t> latest_{-1};
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_ = false;
  std::thread thread_;
};

}  // namespace motormix::node
