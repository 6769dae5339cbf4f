#include "sim/result_json.hpp"

#include <motormix/safety/spinning_descent.hpp>

namespace motormix::sim {

nlohmann::json flight_errors_json(const SimResult& r, bool wheeled) {
  nlohmann::json j;
  j["crashed"] = r.crashed;
  if (r.crashed) {
    j["crash_reason"] = r.crash_reason;
    j["crash_time_s"] = r.crash_time_s;
  }
  if (wheeled) {
    j["speed_error_rms_mps"] = r.speed_error_rms_mps;
    j["yaw_rate_error_rms_dps"] = r.yaw_rate_error_rms_dps;
  }
  j["attitude_error_rms_deg"] = r.attitude_error_rms_deg;
  j["attitude_error_max_deg"] = r.attitude_error_max_deg;
  j["yaw_error_rms_deg"] = r.yaw_error_rms_deg;
  j["altitude_loss_m"] = r.altitude_loss_m;
  j["saturated_fraction"] = r.saturated_fraction;
  return j;
}

nlohmann::json result_json(const SimResult& r, bool wheeled) {
  nlohmann::json j = flight_errors_json(r, wheeled);
  j["armed_s"] = r.armed_s;
  if (!wheeled) {
    j["reached_altitude"] = r.reached_altitude;
    j["altitude_error_max_m"] = r.altitude_error_max_m;
    j["failure_attitude_error_max_deg"] = r.failure_attitude_error_max_deg;
    const auto or_null = [](double v) { return v >= 0 ? nlohmann::json(v) : nlohmann::json(); };
    j["touchdown_speed_mps"] = or_null(r.touchdown_speed_mps);
    j["touchdown_time_s"] = or_null(r.touchdown_time_s);
    j["drift_m"] = r.drift_m;
    j["max_spin_rate_rad_s"] = r.max_spin_rate_rad_s;
    j["max_thrust_axis_tilt_deg"] = r.max_thrust_axis_tilt_deg;
  }
  j["min_battery_v"] = r.min_battery_v;
  j["final_charge"] = r.final_charge;
  j["failsafe_events"] = r.failsafe_events;
  j["cycles"] = r.cycles;
  j["sim_seconds"] = r.sim_seconds;
  j["wall_seconds"] = r.wall_seconds;
  j["realtime_factor"] = r.wall_seconds > 0 ? r.sim_seconds / r.wall_seconds : 0.0;
  return j;
}

nlohmann::json failures_json(const std::vector<FailureOutcome>& outcomes,
                             const config::Config& config, bool undetected) {
  nlohmann::json failures = nlohmann::json::array();
  const auto name = [&](int m) { return config.motor_names()[static_cast<std::size_t>(m)]; };
  for (const FailureOutcome& o : outcomes) {
    nlohmann::json f = {{"motor", name(o.failure.motor)},
                        {"at_s", o.failure.at_s},
                        {"kind", to_string(o.failure.kind)},
                        {"reported", !undetected && reported_outside(o.failure.kind)}};
    f["detected_at_s"] = o.detected_at_s >= 0 ? nlohmann::json(o.detected_at_s) : nlohmann::json();
    f["detected_motor"] =
        o.detected_motor >= 0 ? nlohmann::json(name(o.detected_motor)) : nlohmann::json();
    f["detected_by"] =
        o.detected_at_s >= 0 ? nlohmann::json(to_string(o.detected_by)) : nlohmann::json();
    failures.push_back(f);
  }
  return failures;
}

void add_detections(nlohmann::json& j, const SimResult& r, const config::Config& config) {
  j["false_detections"] = r.false_detections;
  nlohmann::json declared = nlohmann::json::array();
  for (const SimResult::Declaration& d : r.declarations) {
    declared.push_back({{"at_s", d.at_s},
                        {"motor", config.motor_names()[static_cast<std::size_t>(d.motor)]},
                        {"by", to_string(d.source)},
                        {"height_m", d.height_m},
                        {"crashed", d.crashed}});
  }
  j["detections"] = declared;
}

void add_spin(nlohmann::json& j, const SimResult& r, const config::Config& config,
              const std::vector<FailureOutcome>& outcomes) {
  if (!config.motor_loss || outcomes.empty() || r.settled_thrust_n.empty()) return;
  const int failed = outcomes.front().failure.motor;
  const SpinEquilibrium& eq = config.motor_loss->equilibria[static_cast<std::size_t>(failed)];
  nlohmann::json thrust = nlohmann::json::array();
  for (int i = 0, w = 0; i < config.motors(); ++i) {
    thrust.push_back(i == failed ? 0.0 : eq.thrust_n[w++]);
  }
  j["spin"] = {
      {"settled", {{"rate_rad_s", r.settled_spin_rate_rad_s}, {"thrust_n", r.settled_thrust_n}}},
      {"equilibrium",
       {{"rate_rad_s", eq.rates.norm()},
        {"thrust_n", thrust},
        {"axis_tilt_deg", eq.axis_tilt_deg}}}};
}

}  // namespace motormix::sim
