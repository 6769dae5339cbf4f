#pragma once
// The scenario in time: the references it asks for, the wind and gusts, and
// which motors have failed how by a given moment. Lockstep and live runs step
// it the same way.

#include "sim/motor_health.hpp"
#include "sim/scenario.hpp"
#include "sim/vehicle_model.hpp"

#include <motormix/config/config.hpp>

#include <cstddef>
#include <utility>
#include <vector>

namespace motormix::sim {

// The scenario's references at time t, and what the events due change.
class ScenarioClock {
 public:
  ScenarioClock(const Scenario& scenario, const config::Config& config,
                const std::vector<MotorFailure>& extra_failures);
  // Applies every event due at t.
  void advance(double t);
  const Reference& reference() const { return ref_; }
  // What each motor can do at t, after the failures due by then.
  const MotorHealth& health(double t);
  Environment environment(double t) const;
  // Failed motors something outside motormix would have reported by t,
  // detection_s after each failure (motor_health.hpp: reported_outside).
  MotorMask detected(double t, double detection_s) const;
  const std::vector<MotorFailure>& failures() const { return failures_; }  // sorted by at_s

 private:
  const Scenario& scenario_;
  std::vector<MotorFailure> failures_;
  std::size_t next_ = 0;
  Reference ref_;
  MotorHealth health_;
  Eigen::Vector3d wind_ = Eigen::Vector3d::Zero();
  std::vector<std::pair<double, Gust>> gusts_;  // (start, gust)
};

}  // namespace motormix::sim
