#include "output/sysfs_pwm_driver.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace motormix::output {

namespace {

bool is_dir(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

long long to_ns(double us) { return std::llround(us * 1000.0); }

}  // namespace

void SysfsPwmDriver::put(const std::string& path, const std::string& value) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
  if (fd < 0) throw std::runtime_error("cannot open " + path + ": " + std::strerror(errno));
  const ssize_t n = ::write(fd, value.data(), value.size());
  const int err = errno;
  ::close(fd);
  if (n != static_cast<ssize_t>(value.size())) {
    throw std::runtime_error("cannot write " + value + " to " + path + ": " + std::strerror(err));
  }
  if (observer_) observer_(path, value);
}

SysfsPwmDriver::SysfsPwmDriver(const config::SysfsPwm& s, double period_us,
                               const std::vector<double>& disarmed_us, WriteObserver observer,
                               double export_wait_s)
    : period_ns_(to_ns(period_us)), observer_(std::move(observer)) {
  const std::string chip = s.root + "/pwmchip" + std::to_string(s.chip);
  if (!is_dir(chip)) throw std::runtime_error(chip + " does not exist (no such PWM chip)");
  for (std::size_t i = 0; i < s.channels.size(); ++i) {
    const std::string dir = chip + "/pwm" + std::to_string(s.channels[i]);
    if (!is_dir(dir)) {
      put(chip + "/export", std::to_string(s.channels[i]));
      // udev makes the directory (and gives it its group) a moment later.
      const auto until =
          std::chrono::steady_clock::now() + std::chrono::duration<double>(export_wait_s);
      while (!is_dir(dir) && std::chrono::steady_clock::now() < until)
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
      if (!is_dir(dir)) throw std::runtime_error(dir + " did not appear after export");
    }
    const double disarmed = i < disarmed_us.size() ? disarmed_us[i] : 1000.0;
    // The kernel refuses a period shorter than the duty cycle already set:
    // a channel left with a long pulse gets duty 0 first.
    try {
      put(dir + "/period", std::to_string(period_ns_));
    } catch (const std::runtime_error&) {
      put(dir + "/duty_cycle", "0");
      put(dir + "/period", std::to_string(period_ns_));
    }
    put(dir + "/duty_cycle", std::to_string(to_ns(disarmed)));
    put(dir + "/enable", "1");
    channel_dirs_.push_back(dir);
    const int fd = ::open((dir + "/duty_cycle").c_str(), O_WRONLY | O_CLOEXEC);
    if (fd < 0)
      throw std::runtime_error("cannot open " + dir + "/duty_cycle: " + std::strerror(errno));
    duty_fds_.push_back(fd);
  }
}

SysfsPwmDriver::~SysfsPwmDriver() {
  for (int fd : duty_fds_) ::close(fd);
}

bool SysfsPwmDriver::write(const double* pulse_us, int count, std::uint32_t /*armed*/) {
  if (count != static_cast<int>(duty_fds_.size())) return false;
  bool ok = true;
  char text[32];
  for (int i = 0; i < count; ++i) {
    const long long ns = std::min(to_ns(pulse_us[i]), period_ns_);
    const int len = std::snprintf(text, sizeof text, "%lld", ns);
    // sysfs attributes take a whole value per write, from offset 0.
    const int fd = duty_fds_[static_cast<std::size_t>(i)];
    if (::pwrite(fd, text, static_cast<std::size_t>(len), 0) != len) {
      ok = false;
      ++failures_;
    } else {
      // A plain file (a test tree) keeps a longer old value's tail; sysfs
      // ignores the truncation.
      if (::ftruncate(fd, len) != 0) errno = 0;
      if (observer_) observer_(channel_dirs_[static_cast<std::size_t>(i)] + "/duty_cycle", text);
    }
  }
  ++writes_;
  return ok;
}

std::string SysfsPwmDriver::describe() const {
  std::ostringstream s;
  s << "sysfs: " << channel_dirs_.size() << " channels, period " << period_ns_ << " ns, " << writes_
    << " writes, " << failures_ << " failed";
  return s.str();
}

}  // namespace motormix::output
