#pragma once
// Datagrams the kernel dropped because a UDP receive buffer was full, in this
// network namespace (the private bus): /proc/net/snmp, Udp RcvbufErrors. A
// message lost there never reached motormix, so it cannot be counted by it;
// the tests that flood the bus tell that loss apart from motormix's own.

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdint>
#include <fstream>
#include <sstream>
#include <string>

namespace motormix::test {

// -1 when the counter cannot be read.
inline long udp_receive_buffer_drops() {
  std::ifstream snmp("/proc/net/snmp");
  std::string names, values;
  for (std::string line; std::getline(snmp, line);) {
    if (line.rfind("Udp:", 0) != 0) continue;
    if (names.empty()) {
      names = line;
    } else {
      values = line;
      break;
    }
  }
  std::istringstream n(names), v(values);
  for (std::string name, value; n >> name && v >> value;) {
    if (name == "RcvbufErrors") return std::stol(value);
  }
  return -1;
}

// A UDP socket of the test's own on LCM's default multicast group, with a
// small receive buffer and never read: during a flood it overflows, and its
// drops are counted against it alone (the drops column of /proc/net/udp for
// its inode). A mixer that reported every socket's drops, not its own, would
// count these too.
class UnreadMulticastSocket {
 public:
  UnreadMulticastSocket(const char* group = "239.255.76.67", int port = 7667) {
    fd_ = ::socket(AF_INET, SOCK_DGRAM, 0);
    if (fd_ < 0) return;
    const int one = 1;
    ::setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    const int small = 4096;
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &small, sizeof small);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(static_cast<std::uint16_t>(port));
    addr.sin_addr.s_addr = htonl(INADDR_ANY);
    ip_mreq mreq{};
    mreq.imr_multiaddr.s_addr = ::inet_addr(group);
    mreq.imr_interface.s_addr = htonl(INADDR_ANY);
    ok_ = ::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0 &&
          ::setsockopt(fd_, IPPROTO_IP, IP_ADD_MEMBERSHIP, &mreq, sizeof mreq) == 0;
  }
  ~UnreadMulticastSocket() {
    if (fd_ >= 0) ::close(fd_);
  }
  UnreadMulticastSocket(const UnreadMulticastSocket&) = delete;
  UnreadMulticastSocket& operator=(const UnreadMulticastSocket&) = delete;
  bool ok() const { return ok_; }

  // The kernel's drops on this socket; -1 when it cannot be found.
  long drops() const {
    struct stat st {};
    if (fd_ < 0 || ::fstat(fd_, &st) != 0) return -1;
    const std::string inode = std::to_string(st.st_ino);
    std::ifstream udp("/proc/net/udp");
    std::string line;
    std::getline(udp, line);  // header
    while (std::getline(udp, line)) {
      std::istringstream fields(line);
      std::string field;
      std::string columns[13];
      int n = 0;
      while (n < 13 && fields >> field) columns[n++] = field;
      if (n == 13 && columns[9] == inode) return std::stol(columns[12]);
    }
    return -1;
  }

 private:
  int fd_ = -1;
  bool ok_ = false;
};

}  // namespace motormix::test
