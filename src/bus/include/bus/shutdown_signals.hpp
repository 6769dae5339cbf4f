#pragma once
// SIGINT, SIGTERM and SIGHUP as a file descriptor, for every motormix
// process: held while the process runs, they can be polled beside the bus
// and never interrupt a write to the pins half-way. Blocked in the calling
// thread (and every thread it starts afterwards) by the constructor; the
// destructor takes what is still pending, closes the descriptor and restores
// the mask it found, so a signal that arrives after the process has made its
// outputs safe ends it as usual.

#include <signal.h>

#include <string>

namespace motormix::bus {

class ShutdownSignals {
 public:
  ShutdownSignals();
  ~ShutdownSignals();
  ShutdownSignals(const ShutdownSignals&) = delete;
  ShutdownSignals& operator=(const ShutdownSignals&) = delete;

  // False when the signals could not be blocked or the descriptor opened:
  // error() says why, and the process should not start.
  bool good() const { return fd_ >= 0; }
  const std::string& error() const { return error_; }

  // For poll(): readable when a signal is pending.
  int fd() const { return fd_; }

  // The signal taken from the descriptor without blocking, or 0. Once one
  // is taken, requested() stays true.
  int take();
  bool requested();
  int last_signal() const { return last_; }

 private:
  sigset_t previous_{};
  int fd_ = -1;
  int last_ = 0;
  bool masked_ = false;
  std::string error_;
};

}  // namespace motormix::bus
