#include "bus/process.hpp"

#include <poll.h>

#include <cerrno>
#include <utility>

namespace motormix::bus {

std::unique_ptr<lcm::LCM> open_bus(const std::string& who, const std::string& url,
                                   std::ostream& log) {
  auto lcm = std::make_unique<lcm::LCM>(url);
  if (lcm->good()) return lcm;
  log << who << ": cannot open LCM" << (url.empty() ? "" : " at " + url)
      << ". For UDP multicast the host needs an interface up and a multicast route "
         "(on a host with only loopback: ip link set lo up; ip route add 224.0.0.0/4 dev lo); "
         "see docs/troubleshooting.md"
      << std::endl;
  return nullptr;
}

int drain(lcm::LCM& lcm, int max) {
  int handled = 0;
  while (handled < max && lcm.handleTimeout(0) > 0) ++handled;
  return handled;
}

Process::Process(std::string who, const std::string& url, std::ostream& log)
    : who_(std::move(who)) {
  if (!signals_.good()) {
    log << who_ << ": " << signals_.error() << std::endl;
    return;
  }
  lcm_ = open_bus(who_, url, log);
}

Woke Process::wait(int timeout_ms, int own0, int own1) {
  pollfd fds[4] = {{lcm_->getFileno(), POLLIN, 0},
                   {signals_.fd(), POLLIN, 0},
                   {own0, POLLIN, 0},
                   {own1, POLLIN, 0}};
  Woke w;
  if (poll(fds, 4, timeout_ms) < 0) {
    if (errno != EINTR) w.error = errno;
    return w;
  }
  w.bus = (fds[0].revents & POLLIN) != 0;
  w.signal = (fds[1].revents & POLLIN) != 0 && signals_.take() != 0;
  w.own[0] = (fds[2].revents & POLLIN) != 0;
  w.own[1] = (fds[3].revents & POLLIN) != 0;
  return w;
}

}  // namespace motormix::bus
