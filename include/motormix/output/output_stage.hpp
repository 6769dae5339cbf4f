#pragma once
// The output stage turns normalized motor commands into what the drivers
// take, one channel per motor: PWM microseconds for ESCs (0..1 -> min..max),
// centred PWM for reversible drives (-1..1 -> min..center..max), or a duty
// cycle plus a direction bit for H-bridges. Whatever it is given, what it
// returns stays inside each channel's range.

#include <motormix/motor_vector.hpp>

#include <motormix/enum_names.hpp>

#include <array>
#include <cstdint>
#include <vector>

namespace motormix {

enum class OutputMode : std::uint8_t {
  kUnipolar,            // command 0..1 -> min..max
  kCentered,            // command -1..1 -> min..center..max
  kMagnitudeDirection,  // |command| 0..1 -> min..max, sign -> direction (+1/-1, 0 at rest)
};
inline constexpr EnumName<OutputMode> kOutputModeNames[] = {
    {OutputMode::kUnipolar, "unipolar"},
    {OutputMode::kCentered, "centered"},
    {OutputMode::kMagnitudeDirection, "magnitude_direction"},
};
inline const char* to_string(OutputMode value) { return name_in(kOutputModeNames, value); }

struct OutputChannel {
  OutputMode mode = OutputMode::kUnipolar;
  double min = 1000.0;       // output at command 0 (unipolar, magnitude) or -1 (centered)
  double max = 2000.0;       // output at command 1
  double center = 1500.0;    // centered mode: output at command 0
  double disarmed = 1000.0;  // output while disarmed or in failsafe
  double idle = 0.0;         // unipolar: command floor while armed, so motors keep spinning
  double trim = 0.0;         // added to the command before mapping
  bool reversed = false;     // unipolar: max..min; bipolar modes: command sign flipped
  // Unipolar: thrust = k x^2 + (1-k) x for output fraction x, so a commanded
  // thrust fraction is produced rather than a commanded PWM (0: linear; 1:
  // thrust proportional to command squared).
  double thrust_model_factor = 0.0;
  double slew_per_s = 0.0;  // largest output change per second while armed; 0: unlimited
};

using DirectionVector = std::array<std::int8_t, kMaxMotors>;

class OutputStage {
 public:
  // Channels are validated by the config layer (min < max, center inside,
  // all finite, factors within range).
  explicit OutputStage(std::vector<OutputChannel> channels);

  int outputs() const { return static_cast<int>(channels_.size()); }
  const OutputChannel& channel(int i) const { return channels_[static_cast<std::size_t>(i)]; }

  // Maps `command` (NaN and infinities count as 0, the safe middle or
  // bottom). With dt_s > 0 and `previous_armed`, each output moves at most
  // slew_per_s * dt_s from its value in `output` (the previous cycle's).
  // Channels in `stopped` (failed motors) get their disarmed value at once,
  // slew limit or not: a dead motor is not driven.
  void armed(const MotorVector& command, MotorVector& output, DirectionVector& direction,
             double dt_s, bool previous_armed, MotorMask stopped = 0) const;
  void disarmed(MotorVector& output, DirectionVector& direction) const;

  // The thrust model: thrust fraction k x^2 + (1 - k) x of output fraction
  // x (0..1), for factor k (also what a simulated or monitored ESC gives).
  static double thrust_of(double x, double factor) { return factor * x * x + (1.0 - factor) * x; }
  // The thrust model inverted: output fraction that produces `thrust` (0..1).
  static double linearize(double thrust, double factor);

 private:
  std::vector<OutputChannel> channels_;
};

}  // namespace motormix
