#include "sim/scenario_clock.hpp"

#include "sim/period.hpp"

#include <motormix/angles.hpp>

#include <algorithm>
#include <cmath>

namespace motormix::sim {

namespace {

double wrap(double angle) { return std::remainder(angle, 2 * kPi); }

}  // namespace

ScenarioClock::ScenarioClock(const Scenario& scenario, const config::Config& config,
                             const std::vector<MotorFailure>& extra_failures)
    : scenario_(scenario) {
  for (const ScenarioEvent& e : scenario.timeline) {
    if (e.fail) failures_.push_back({*e.fail, e.at_s, e.fail_kind});
  }
  for (const MotorFailure& f : extra_failures) failures_.push_back(f);
  std::stable_sort(failures_.begin(), failures_.end(),
                   [](const MotorFailure& a, const MotorFailure& b) { return a.at_s < b.at_s; });
  for (const MotorFailure& f : failures_) {
    if (f.motor < 0 || f.motor >= config.motors()) {
      throw config::ConfigError("motor " + std::to_string(f.motor + 1) +
                                " to fail: the vehicle has motors 1 to " +
                                std::to_string(config.motors()));
    }
  }
  ref_.armed = false;
  ref_.altitude_m = scenario.altitude_m;
  health_ = MotorHealth::healthy(config.motors());
}

const MotorHealth& ScenarioClock::health(double t) {
  health_.drive.setOnes();
  health_.prop.setOnes();
  health_.telemetry_dead = 0;
  for (const MotorFailure& f : failures_) {
    if (f.at_s > t) break;  // as the timeline's events: due once t reaches them
    health_.apply(f, t);
  }
  return health_;
}

void ScenarioClock::advance(double t) {
  ref_.armed = t >= scenario_.arm_at_s;
  while (next_ < scenario_.timeline.size() && scenario_.timeline[next_].at_s <= t) {
    const ScenarioEvent& e = scenario_.timeline[next_++];
    if (e.roll_deg) ref_.roll = *e.roll_deg * kRadPerDeg;
    if (e.pitch_deg) ref_.pitch = *e.pitch_deg * kRadPerDeg;
    if (e.yaw_deg) ref_.yaw = wrap(*e.yaw_deg * kRadPerDeg);
    if (e.altitude_m) ref_.altitude_m = *e.altitude_m;
    if (e.speed_mps) ref_.speed_mps = *e.speed_mps;
    if (e.yaw_rate_dps) ref_.yaw_rate = *e.yaw_rate_dps * kRadPerDeg;
    if (e.wind_mps) wind_ = *e.wind_mps;
    if (e.gust) gusts_.emplace_back(e.at_s, *e.gust);
  }
}

MotorMask ScenarioClock::detected(double t, double detection_s) const {
  MotorMask mask = 0;
  for (const MotorFailure& f : failures_) {
    if (reported_outside(f.kind) && due(t, f.at_s + detection_s)) mask |= MotorMask{1} << f.motor;
  }
  return mask;
}

Environment ScenarioClock::environment(double t) const {
  Environment env;
  env.wind_ned = wind_;
  for (const auto& [start, g] : gusts_) {
    if (t >= start && t < start + g.for_s) {
      env.force_world += g.force_n;
      env.torque_body += g.torque_nm;
    }
  }
  return env;
}

}  // namespace motormix::sim
