#include "bus/process.hpp"

#include <poll.h>

#include <cerrno>
#include <ctime>
#include <stdexcept>
#include <string>
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

std::size_t Process::watch(int fd) {
  if (watched_ >= kMaxWatched)
    throw std::length_error(who_ + ": more than " + std::to_string(kMaxWatched) +
                            " descriptors to watch");
  watched_fds_[watched_] = fd;
  return watched_++;
}

Woke Process::wait_ns(std::int64_t timeout_ns) {
  pollfd fds[2 + kMaxWatched];
  const std::size_t n = 2 + watched_;
  fds[0] = {lcm_->getFileno(), POLLIN, 0};
  fds[1] = {signals_.fd(), POLLIN, 0};
  for (std::size_t i = 0; i < watched_; ++i) fds[2 + i] = {watched_fds_[i], POLLIN, 0};
  timespec wait{};
  if (timeout_ns >= 0) {
    wait.tv_sec = static_cast<time_t>(timeout_ns / 1'000'000'000);
    wait.tv_nsec = static_cast<long>(timeout_ns % 1'000'000'000);
  }
  Woke w;
  if (ppoll(fds, n, timeout_ns >= 0 ? &wait : nullptr, nullptr) < 0) {
    if (errno != EINTR) w.error = errno;
    return w;
  }
  w.bus = (fds[0].revents & POLLIN) != 0;
  w.signal = (fds[1].revents & POLLIN) != 0 && signals_.take() != 0;
  for (std::size_t i = 0; i < watched_; ++i) w.own[i] = (fds[2 + i].revents & POLLIN) != 0;
  return w;
}

}  // namespace motormix::bus
