#include <motormix/config/hover_point.hpp>

#include <motormix/gravity.hpp>
#include <motormix/output/output_stage.hpp>

#include <algorithm>
#include <cstddef>

namespace motormix::config {

namespace {

// Bisection on a monotonic curve of 0..1: 1e-9 of the throttle's range.
constexpr int kBisections = 30;

}  // namespace

HoverPoint hover_point(const Config& config) {
  HoverPoint h;
  const VehiclePhysics& v = config.vehicle_model;
  // Only from the configuration's own weight and thrust: the defaults a
  // geometry gives a vehicle hover wherever they were chosen to.
  if (v.wheeled || !v.incomplete.empty() || v.rotors.empty() || !v.weight_and_thrust_given ||
      !(v.mass_kg > 0.0))
    return h;
  double lift = 0.0;  // upward force at full thrust fraction, N
  for (const RotorPhysics& r : v.rotors) lift += r.max_thrust_n * -r.axis.z();
  if (!(lift > 0.0)) return h;
  h.thrust = v.mass_kg * kStandardGravity / lift;
  if (h.thrust >= 1.0) return h;  // cannot lift itself: no hover to gate on
  // Upward force at throttle t: each motor's output through its channel,
  // then the ESC's input fraction through its curve.
  const auto upward_share = [&](double t) {
    double up = 0.0;
    for (std::size_t i = 0; i < v.rotors.size() && i < config.outputs.size(); ++i) {
      const OutputChannel& ch = config.outputs[i];
      double x = OutputStage::linearize(t, ch.thrust_model_factor);
      x = ch.idle + (1.0 - ch.idle) * x;
      const double output = ch.min + x * (ch.max - ch.min);
      const double esc_min = i < v.esc_min.size() ? v.esc_min[i] : ch.min;
      const double esc_max = i < v.esc_max.size() ? v.esc_max[i] : ch.max;
      const double y =
          esc_max > esc_min ? std::clamp((output - esc_min) / (esc_max - esc_min), 0.0, 1.0) : x;
      up += OutputStage::thrust_of(y, v.thrust_expo) * v.rotors[i].max_thrust_n *
            -v.rotors[i].axis.z();
    }
    return up / lift;
  };
  if (upward_share(1.0) < h.thrust) return h;  // the output range never reaches hover
  double lo = 0.0, hi = 1.0;
  for (int k = 0; k < kBisections; ++k) {
    const double mid = 0.5 * (lo + hi);
    (upward_share(mid) < h.thrust ? lo : hi) = mid;
  }
  h.throttle = hi;
  h.known = true;
  return h;
}

}  // namespace motormix::config
