#pragma once
// The failure detector inside the control loop: it turns accepted ESC
// telemetry (eRPM into rpm with the configured pole count) and attitude
// samples into the detector's inputs, and the outputs the loop sent into
// each motor's thrust fraction through the vehicle's ESC curve (the
// `vehicle:` section's esc_min, esc_max and thrust_expo). When detection is
// allowed is the loop's call (control_loop.hpp).

#include "loop/esc_curve.hpp"
#include "loop/input_samples.hpp"
#include "loop/latest_input.hpp"

#include <motormix/config/config.hpp>
#include <motormix/safety/failure_detector.hpp>

#include <array>
#include <cstdint>
#include <vector>

namespace motormix::loop {

class DetectionRunner {
 public:
  // config.failure_detection must be set.
  explicit DetectionRunner(const config::Config& config);

  bool uses_telemetry() const { return detector_.uses(DetectorSources::kTelemetry); }
  bool uses_rates() const { return detector_.uses(DetectorSources::kRates); }
  double min_throttle() const { return min_throttle_; }

  // The readings whose bit is set in `taken` (check_esc_telemetry's verdict).
  void on_telemetry(const EscTelemetrySample& sample, std::uint32_t taken, std::int64_t now_us);
  void on_attitude(const AttitudeSample& sample, std::int64_t now_us);

  // outputs: the output-stage values the motors are running on (the
  // previous cycle's).
  const Detection& update(const MotorVector& outputs, MotorMask excluded, bool allowed,
                          std::int64_t now_us);
  void reset() { detector_.reset(); }
  const Detection& detection() const { return detector_.detection(); }
  const FailureDetector& detector() const { return detector_; }

 private:
  FailureDetector detector_;
  double min_throttle_;
  double pole_pairs_;
  EscCurve curve_;
  MotorVector thrust_;
};

}  // namespace motormix::loop
