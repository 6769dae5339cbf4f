#include "integration/process.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <string>

#include <thread>

namespace motormix::test {

namespace {

// PATH lookup done in the parent, before fork.
std::string resolve(const std::string& name) {
  if (name.find('/') != std::string::npos) return name;
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "/usr/bin:/bin";
  std::size_t start = 0;
  while (start <= dirs.size()) {
    const std::size_t end = dirs.find(':', start);
    const std::string dir =
        dirs.substr(start, end == std::string::npos ? std::string::npos : end - start);
    const std::string candidate = (dir.empty() ? "." : dir) + "/" + name;
    if (access(candidate.c_str(), X_OK) == 0) return candidate;
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return name;
}

}  // namespace

ChildProcess::ChildProcess(const std::vector<std::string>& argv, const std::string& stderr_path) {
  const int err_fd = stderr_path.empty() ? -1
                                         : ::open(stderr_path.c_str(),
                                                  O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const std::string program = resolve(argv[0]);
  pid_ = fork();
  if (pid_ == 0) {
    // Only async-signal-safe calls between fork and exec (the test has
    // threads). The child dies with the test: a test killed by its timeout
    // leaves no mixer running.
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (err_fd >= 0) dup2(err_fd, STDERR_FILENO);
    execv(program.c_str(), args.data());
    _exit(127);
  }
  if (err_fd >= 0) ::close(err_fd);
}

ChildProcess::~ChildProcess() {
  if (started() && running()) {
    ::kill(pid_, SIGKILL);
    wait_for(std::chrono::milliseconds(5000));
  }
}

bool ChildProcess::running() {
  if (!started() || reaped_) return false;
  if (waitpid(pid_, &status_, WNOHANG) == pid_) reaped_ = true;
  return !reaped_;
}

void ChildProcess::signal(int signo) {
  if (running()) ::kill(pid_, signo);
}

std::optional<int> ChildProcess::wait_for(std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (running()) {
    if (std::chrono::steady_clock::now() > deadline) return std::nullopt;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));  // polling a child's exit
  }
  if (!reaped_ || !WIFEXITED(status_)) return std::nullopt;
  return WEXITSTATUS(status_);
}

}  // namespace motormix::test
