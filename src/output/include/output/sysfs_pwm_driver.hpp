#pragma once
// Linux hardware PWM through sysfs (/sys/class/pwm/pwmchipN; Raspberry Pi,
// BeagleBone, Jetson), in the order the kernel documents: export the
// channel (and wait for udev to make its directory), period, duty_cycle,
// enable. Each write then sets duty_cycle only. The root is configurable,
// so the tests drive a tree in a temporary directory.
//
// A PWM peripheral keeps its last duty cycle when the process dies: after
// SIGKILL the motors stay at their last pulse. `motormix output --disarm`
// (for a supervisor's stop hook) writes the disarmed pulses and exits.

#include "output/pulse_driver.hpp"

#include <motormix/config/hardware.hpp>

#include <functional>
#include <string>
#include <vector>

namespace motormix::output {

class SysfsPwmDriver : public PulseDriver {
 public:
  // Told of every write (path, value), after it: the tests check the order.
  using WriteObserver = std::function<void(const std::string&, const std::string&)>;

  // Exports and sets up every channel, with the disarmed pulses; throws
  // std::runtime_error naming the file and the reason.
  SysfsPwmDriver(const config::SysfsPwm& settings, double period_us,
                 const std::vector<double>& disarmed_us, WriteObserver observer = {},
                 double export_wait_s = 1.0);
  ~SysfsPwmDriver() override;
  SysfsPwmDriver(const SysfsPwmDriver&) = delete;
  SysfsPwmDriver& operator=(const SysfsPwmDriver&) = delete;

  bool write(const double* pulse_us, int count, std::uint32_t armed) override;
  std::string describe() const override;

 private:
  void put(const std::string& path, const std::string& value);

  std::vector<std::string> channel_dirs_;
  std::vector<int> duty_fds_;
  long long period_ns_;
  WriteObserver observer_;
  std::uint64_t writes_ = 0, failures_ = 0;
};

}  // namespace motormix::output
