#pragma once
// Datagrams the kernel dropped on this process's own UDP sockets because
// their receive buffer was full: the "drops" column of /proc/net/udp and
// /proc/net/udp6 for the socket inodes among /proc/self/fd. A message lost
// there never reached LCM, so no counter of motormix's could see it;
// mixer_status_t reports this one as kernel_drops. (LCM 1.3.1 also drops
// silently when a subscription's queue is full; that loss is not visible
// from outside LCM.)

#include <cstdint>

namespace motormix::node {

// Since the sockets were opened; -1 when /proc cannot be read (no procfs,
// or no UDP socket of this process in the tables).
std::int64_t own_udp_socket_drops();

}  // namespace motormix::node
