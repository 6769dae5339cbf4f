#include <motormix/output_stage.hpp>

#include <algorithm>
#include <cmath>
#include <utility>

namespace motormix {

OutputStage::OutputStage(std::vector<OutputChannel> channels) : channels_(std::move(channels)) {}

void OutputStage::armed(const MotorVector& command, MotorVector& output) const {
  output.resize(outputs());
  for (int i = 0; i < outputs(); ++i) {
    const OutputChannel& ch = channels_[static_cast<std::size_t>(i)];
    const double c = std::isfinite(command[i]) ? std::clamp(command[i], 0.0, 1.0) : 0.0;
    // min + c*(max-min) can round a hair past max; the clamp keeps the promise.
    output[i] = std::clamp(ch.min + c * (ch.max - ch.min), ch.min, ch.max);
  }
}

void OutputStage::disarmed(MotorVector& output) const {
  output.resize(outputs());
  for (int i = 0; i < outputs(); ++i) {
    output[i] = channels_[static_cast<std::size_t>(i)].disarmed;
  }
}

}  // namespace motormix
