#pragma once
// Datagrams the kernel dropped because a UDP receive buffer was full, in this
// network namespace (the private bus): /proc/net/snmp, Udp RcvbufErrors. A
// message lost there never reached motormix, so it cannot be counted by it;
// the tests that flood the bus tell that loss apart from motormix's own.

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

}  // namespace motormix::test
