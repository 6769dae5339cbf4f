#include "loop/detection_runner.hpp"

#include <algorithm>
#include <cmath>

namespace motormix::loop {

DetectionRunner::DetectionRunner(const config::Config& config)
    : detector_(config.failure_detection->detector),
      min_throttle_(config.failure_detection->min_throttle),
      pole_pairs_(config.failure_detection->motor_poles / 2.0),
      expo_(config.vehicle_model.thrust_expo),
      esc_min_(config.vehicle_model.esc_min),
      esc_max_(config.vehicle_model.esc_max) {
  // Without a vehicle section's ESC range, the output stage's own.
  esc_min_.resize(static_cast<std::size_t>(config.motors()));
  esc_max_.resize(static_cast<std::size_t>(config.motors()));
  for (std::size_t i = 0; i < config.outputs.size() && i < esc_min_.size(); ++i) {
    if (!(esc_max_[i] > esc_min_[i])) {
      esc_min_[i] = config.outputs[i].min;
      esc_max_[i] = config.outputs[i].max;
    }
  }
  thrust_.setZero(config.motors());
}

void DetectionRunner::on_telemetry(const EscTelemetrySample& sample, std::int64_t now_us) {
  for (int i = 0; i < sample.count; ++i) {
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
    const auto k = static_cast<std::size_t>(i);
    const double x =
        i < outputs.size()
            ? std::clamp((outputs[i] - esc_min_[k]) / (esc_max_[k] - esc_min_[k]), 0.0, 1.0)
            : 0.0;
    thrust_[i] = OutputStage::thrust_of(x, expo_);
  }
  return detector_.update(thrust_, excluded, allowed, now_us);
}

}  // namespace motormix::loop
