#include <motormix/output/output_stage.hpp>

#include <algorithm>
#include <cmath>
#include <utility>

namespace motormix {

OutputStage::OutputStage(std::vector<OutputChannel> channels) : channels_(std::move(channels)) {}

double OutputStage::linearize(double thrust, double factor) {
  if (factor <= 0.0) return thrust;
  // Solve k x^2 + (1-k) x - thrust = 0 for the root in 0..1.
  const double b = 1.0 - factor;
  return (-b + std::sqrt(b * b + 4.0 * factor * thrust)) / (2.0 * factor);
}

void OutputStage::armed(const MotorVector& command, MotorVector& output, DirectionVector& direction,
                        double dt_s, bool previous_armed, MotorMask stopped) const {
  const bool limit_slew = previous_armed && dt_s > 0.0 && output.size() == outputs();
  MotorVector previous = output;
  output.resize(outputs());
  for (int i = 0; i < outputs(); ++i) {
    const OutputChannel& ch = channels_[static_cast<std::size_t>(i)];
    if ((stopped >> i) & 1U) {
      output[i] = ch.disarmed;  // the stop value, as when disarmed
      direction[static_cast<std::size_t>(i)] = 0;
      continue;
    }
    const double c_in = std::isfinite(command[i]) ? command[i] : 0.0;
    double value = ch.disarmed;
    std::int8_t dir = 0;
    switch (ch.mode) {
      case OutputMode::kUnipolar: {
        double x = linearize(std::clamp(c_in, 0.0, 1.0), ch.thrust_model_factor);
        x = std::clamp(x + ch.trim, 0.0, 1.0);
        x = ch.idle + (1.0 - ch.idle) * x;
        if (ch.reversed) x = 1.0 - x;
        value = ch.min + x * (ch.max - ch.min);
        break;
      }
      case OutputMode::kCentered: {
        double c = std::clamp((ch.reversed ? -c_in : c_in) + ch.trim, -1.0, 1.0);
        value =
            c >= 0.0 ? ch.center + c * (ch.max - ch.center) : ch.center + c * (ch.center - ch.min);
        break;
      }
      case OutputMode::kMagnitudeDirection: {
        const double c = std::clamp((ch.reversed ? -c_in : c_in) + ch.trim, -1.0, 1.0);
        value = ch.min + std::abs(c) * (ch.max - ch.min);
        dir = c > 0.0 ? 1 : (c < 0.0 ? -1 : 0);
        break;
      }
    }
    if (limit_slew && ch.slew_per_s > 0.0) {
      const double step = ch.slew_per_s * dt_s;
      value = std::clamp(value, previous[i] - step, previous[i] + step);
    }
    // Rounding (or a slew from a disarmed value) may sit a hair outside: the
    // clamp keeps the promise.
    output[i] = std::clamp(value, ch.min, ch.max);
    direction[static_cast<std::size_t>(i)] = dir;
  }
}

void OutputStage::disarmed(MotorVector& output, DirectionVector& direction) const {
  output.resize(outputs());
  for (int i = 0; i < outputs(); ++i) {
    output[i] = channels_[static_cast<std::size_t>(i)].disarmed;
    direction[static_cast<std::size_t>(i)] = 0;
  }
}

}  // namespace motormix
