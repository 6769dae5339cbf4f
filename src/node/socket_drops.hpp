#pragma once
// Datagrams the kernel dropped on this process's own UDP sockets because
// their receive buffer was full: the "drops" column of /proc/net/udp and
// /proc/net/udp6 for the socket inodes among /proc/self/fd. A message lost
// there never reached LCM, so no counter of motormix's could see it;
// mixer_status_t reports this one as kernel_drops. (LCM 1.3.1 also drops
// silently when a subscription's queue is full; that loss is not visible
// from outside LCM.)

#include <cstdint>
#include <vector>

namespace motormix::node {

class SocketDrops {
 public:
  // Since the sockets were opened; -1 when /proc cannot be read (no procfs,
  // or no UDP socket of this process in the tables yet). The process's
  // sockets are looked up in /proc/self/fd until found, then remembered: a
  // read is then one pass over the UDP tables.
  std::int64_t read();

 private:
  std::vector<unsigned long> inodes_;
};

}  // namespace motormix::node
