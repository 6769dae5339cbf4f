#include "loop/detection_runner.hpp"

#include <algorithm>
#include <cmath>

namespace motormix::loop {

DetectionRunner::DetectionRunner(const config::Config& config)
    : detector_(config.failure_detection->detector),
      min_throttle_(config.failure_detection->min_throttle),
      pole_pairs_(config.failure_detection->motor_poles / 2.0),
      curve_(esc_curve_of(config)) {
  thrust_.setZero(config.motors());
}

void DetectionRunner::on_telemetry(const EscTelemetrySample& sample, std::uint32_t taken,
                                   std::int64_t now_us) {
  for (int i = 0; i < sample.count; ++i) {
    if (((taken >> i) & 1U) == 0) continue;
    const EscReading& r = sample.readings[static_cast<std::size_t>(i)];
    const double rpm = std::isfinite(r.rpm) ? r.rpm : r.erpm / pole_pairs_;  // NaN stays NaN
    detector_.on_telemetry(r.motor - 1, rpm, r.current_a, now_us);
  }
}

void DetectionRunner::on_attitude(const AttitudeSample& sample, std::int64_t now_us) {
  detector_.on_rates(Eigen::Vector3d(sample.rates[0], sample.rates[1], sample.rates[2]),
                     sample.utime, now_us);
}

const Detection& DetectionRunner::update(const MotorVector& outputs, MotorMask excluded,
                                         bool allowed, std::int64_t now_us) {
  for (Eigen::Index i = 0; i < thrust_.size(); ++i) {
    thrust_[i] =
        i < outputs.size() ? curve_.thrust_of(static_cast<std::size_t>(i), outputs[i]) : 0.0;
  }
  return detector_.update(thrust_, excluded, allowed, now_us);
}

}  // namespace motormix::loop
