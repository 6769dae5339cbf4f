#pragma once
// What each motor's ESC makes of an output-stage value, as the vehicle's
// `vehicle:` section describes it (esc_min, esc_max, thrust_expo): the
// thrust fraction a value gives (the failure detector's view of the
// outputs) and the value that gives a thrust fraction (the spin landing's
// commands). One curve for both, so they cannot disagree.

#include <motormix/config/config.hpp>
#include <motormix/output/output_stage.hpp>

#include <algorithm>
#include <cstddef>
#include <vector>

namespace motormix::loop {

struct EscCurve {
  std::vector<double> min, max;  // per motor, in the output unit: thrust 0 and full
  double expo = 0.0;

  // Thrust fraction (0..1) of output value `output` on motor i.
  double thrust_of(std::size_t i, double output) const {
    return OutputStage::thrust_of(std::clamp((output - min[i]) / (max[i] - min[i]), 0.0, 1.0),
                                  expo);
  }
  // Output value that gives thrust fraction `thrust` (clamped to 0..1) on motor i.
  double output_of(std::size_t i, double thrust) const {
    return min[i] + OutputStage::linearize(std::clamp(thrust, 0.0, 1.0), expo) * (max[i] - min[i]);
  }
};

// The curve of a configuration: its vehicle section's ESC range, or, for a
// motor without one, the output stage's own range.
inline EscCurve esc_curve_of(const config::Config& config) {
  EscCurve c{config.vehicle_model.esc_min, config.vehicle_model.esc_max,
             config.vehicle_model.thrust_expo};
  c.min.resize(static_cast<std::size_t>(config.motors()));
  c.max.resize(static_cast<std::size_t>(config.motors()));
  for (std::size_t i = 0; i < config.outputs.size() && i < c.min.size(); ++i) {
    if (!(c.max[i] > c.min[i])) {
      c.min[i] = config.outputs[i].min;
      c.max[i] = config.outputs[i].max;
    }
  }
  return c;
}

}  // namespace motormix::loop
