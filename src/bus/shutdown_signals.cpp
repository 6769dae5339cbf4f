#include "bus/shutdown_signals.hpp"

#include <sys/signalfd.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace motormix::bus {

namespace {
sigset_t shutdown_set() {
  sigset_t s;
  sigemptyset(&s);
  sigaddset(&s, SIGINT);
  sigaddset(&s, SIGTERM);
  sigaddset(&s, SIGHUP);
  return s;
}
}  // namespace

ShutdownSignals::ShutdownSignals() {
  const sigset_t set = shutdown_set();
  // pthread_sigmask: the mask of this thread, which threads started later inherit.
  if (const int e = pthread_sigmask(SIG_BLOCK, &set, &previous_); e != 0) {
    error_ = std::string("cannot block SIGINT/SIGTERM/SIGHUP: ") + std::strerror(e);
    return;
  }
  masked_ = true;
  fd_ = signalfd(-1, &set, SFD_CLOEXEC | SFD_NONBLOCK);
  if (fd_ < 0) error_ = std::string("cannot open a signal descriptor: ") + std::strerror(errno);
}

ShutdownSignals::~ShutdownSignals() {
  if (fd_ >= 0) {
    while (take() != 0) {
    }
    close(fd_);
  }
  if (masked_) pthread_sigmask(SIG_SETMASK, &previous_, nullptr);
}

int ShutdownSignals::take() {
  if (fd_ < 0) return 0;
  signalfd_siginfo info{};
  if (read(fd_, &info, sizeof info) != static_cast<ssize_t>(sizeof info)) return 0;
  last_ = static_cast<int>(info.ssi_signo);
  return last_;
}

bool ShutdownSignals::requested() {
  take();
  return last_ != 0;
}

}  // namespace motormix::bus
