#pragma once
// What `motormix output` drives: the pulse firmware over a serial port or
// Linux hardware PWM. One call per decision, with every motor's pulse in
// microseconds (already the disarmed ones when not armed).

#include <string>

namespace motormix::output {

class PulseDriver {
 public:
  virtual ~PulseDriver() = default;
  // False when the hardware refused the values (counted by the caller).
  virtual bool write(const double* pulse_us, int count, bool armed) = 0;
  // Work between writes (reading the firmware's reports); false on a lost
  // device.
  virtual bool service(double now_s) {
    (void)now_s;
    return true;
  }
  // One line on the hardware's own state, for the log.
  virtual std::string describe() const = 0;
};

}  // namespace motormix::output
