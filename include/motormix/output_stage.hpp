#pragma once
// The output stage turns normalized motor commands (0..1) into the unit the
// motor drivers take (PWM microseconds by default), one channel per motor.
// Whatever it is given, what it returns stays inside each channel's range.

#include <motormix/motor_vector.hpp>

#include <vector>

namespace motormix {

struct OutputChannel {
  double min = 1000.0;       // output at command 0 while armed
  double max = 2000.0;       // output at command 1
  double disarmed = 1000.0;  // output while disarmed or in failsafe
};

class OutputStage {
 public:
  // Channels are validated by the config layer (min < max, all finite).
  explicit OutputStage(std::vector<OutputChannel> channels);

  int outputs() const { return static_cast<int>(channels_.size()); }
  const OutputChannel& channel(int i) const { return channels_[static_cast<std::size_t>(i)]; }

  // Linear map of command (clamped to 0..1; NaN and infinities count as 0,
  // the safe end) to each channel's min..max.
  void armed(const MotorVector& command, MotorVector& output) const;
  void disarmed(MotorVector& output) const;

 private:
  std::vector<OutputChannel> channels_;
};

}  // namespace motormix
