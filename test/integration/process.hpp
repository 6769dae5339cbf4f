#pragma once
// Child processes for integration tests: spawn, signal, and wait with a
// bounded timeout (a hung child is killed, never waited on forever).

#include <sys/types.h>

#include <chrono>
#include <optional>
#include <string>
#include <vector>

namespace motormix::test {

class ChildProcess {
 public:
  // stderr_path: where the child's standard error goes (empty: inherited).
  explicit ChildProcess(const std::vector<std::string>& argv, const std::string& stderr_path = "");
  ~ChildProcess();  // kills the child if it is still running
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  bool started() const { return pid_ > 0; }
  ::pid_t pid() const { return pid_; }
  bool running();
  void signal(int signo);
  // Exit code if the child exited within `timeout`; nullopt otherwise (or if
  // it died from a signal).
  std::optional<int> wait_for(std::chrono::milliseconds timeout);

 private:
  ::pid_t pid_ = -1;
  bool reaped_ = false;
  int status_ = 0;
};

}  // namespace motormix::test
