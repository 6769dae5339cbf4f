// The `failure_detection:` section (documented in docs/motor-failures.md).

#include "failure_detection_reader.hpp"

#include <motormix/config/hover_point.hpp>
#include <motormix/gravity.hpp>

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>

namespace motormix::config {

namespace {

// The outputs-only source needs this many rotors: with fewer, the vehicle
// does not live through the second it takes to decide.
constexpr int kOutputsMinRotors = 6;
// Rotors from which losing one leaves every axis held (hexa, octo).
constexpr int kReallocatingRotors = 6;
// Default smallest rates residual judged, as a fraction of the smallest
// torque one motor gives at hover: gusts and model error stay below it.
constexpr double kMinResidualOfHoverTorque = 0.3;
// The gates that must be open in hover default to fractions of it: the
// setpoint throttle (min_throttle) and each motor's thrust fraction
// (min_motor_thrust). Half the hover throttle is on the ground or climbing
// off it; a sixth of a motor's hover thrust (0.08 on a vehicle hovering at
// half thrust) is where its rpm, 40 % of its hover rpm, still stands well
// above the ESC's idle noise. Without a vehicle that hovers, the fixed
// defaults (a quad hovering near half throttle).
constexpr double kMinThrottleOfHover = 0.5;
constexpr double kMinMotorThrustOfHover = 0.16;
constexpr double kMinThrottleFallback = 0.25;
constexpr double kMinMotorThrustFallback = 0.08;

std::uint8_t bit(DetectorSources s) { return static_cast<std::uint8_t>(s); }

std::uint8_t read_sources(MapReader& section) {
  // The outputs source is opt-in: in the simulator it saves no hexa and
  // declares healthy motors in hard manoeuvres (docs/failure-detection.md).
  const std::uint8_t fallback = bit(DetectorSources::kTelemetry) | bit(DetectorSources::kRates);
  const YAML::Node node = section.raw("sources");
  if (!node.IsDefined() || node.IsNull()) return fallback;
  const std::string path = section.path_of("sources");
  const std::string allowed =
      "a list of " + joined_names(kDetectorSourcesNames) + " (at least one)";
  if (!node.IsSequence() || node.size() == 0) fail(path, describe(node), allowed);
  std::uint8_t sources = 0;
  for (std::size_t i = 0; i < node.size(); ++i) {
    const std::string item_path = path + "[" + std::to_string(i) + "]";
    if (!node[i].IsScalar()) fail(item_path, describe(node[i]), allowed);
    const std::string name = node[i].as<std::string>();
    const std::optional<DetectorSources> source = parse_in(kDetectorSourcesNames, name);
    if (!source) fail(item_path, "'" + name + "'", "one of " + joined_names(kDetectorSourcesNames));
    sources |= bit(*source);
  }
  return sources;
}

}  // namespace

void rotor_momentum_model(const VehiclePhysics& v, FailureDetectorSettings& s) {
  s.momentum_per_speed.setZero(3, static_cast<Eigen::Index>(v.rotors.size()));
  for (std::size_t i = 0; i < v.rotors.size(); ++i) {
    const RotorPhysics& r = v.rotors[i];
    s.momentum_per_speed.col(static_cast<Eigen::Index>(i)) =
        static_cast<double>(r.spin) * v.rotor_inertia_kgm2 * r.axis;
  }
  s.max_rotor_speed_rad_s = v.max_rotor_speed_rad_s;
}

namespace {

// Torque of each rotor at full thrust fraction, as the simulator's vehicle
// makes it: the thrust's moment about the centre of mass and the drag
// torque against the spin.
void rates_scale(const VehiclePhysics& v, FailureDetectorSettings& s) {
  s.torque_per_thrust.setZero(3, static_cast<Eigen::Index>(v.rotors.size()));
  double lift = 0.0;
  for (std::size_t i = 0; i < v.rotors.size(); ++i) {
    const RotorPhysics& r = v.rotors[i];
    const Eigen::Vector3d f = r.max_thrust_n * r.axis;
    s.torque_per_thrust.col(static_cast<Eigen::Index>(i)) =
        r.position_m.cross(f) + static_cast<double>(r.spin) * r.torque_ratio_m * -f;
    lift += -f.z();
  }
  s.inertia_kgm2 = v.inertia_kgm2;
  s.rotational_drag = v.drag_rotational_nm_per_radps;
  rotor_momentum_model(v, s);
  const double hover = lift > 0 ? std::clamp(v.mass_kg * kStandardGravity / lift, 0.05, 1.0) : 0.5;
  double smallest = 0.0;
  for (Eigen::Index i = 0; i < s.torque_per_thrust.cols(); ++i) {
    const double t = s.torque_per_thrust.col(i).norm() * hover;
    if (i == 0 || t < smallest) smallest = t;
  }
  s.min_residual_nm = kMinResidualOfHoverTorque * smallest;
}

}  // namespace

void read_failure_detection(MapReader section, bool present, Config& config) {
  // Every key is read (and so documented) whether or not the section is
  // there; only an enabled section is checked against the vehicle and kept.
  const bool enabled = section.boolean("enabled", true) && present;
  if (enabled && config.thrust_range() == ThrustRange::kBipolar) {
    fail(section.path_of("enabled"), "true, on a ground vehicle",
         "false: detection is for aircraft (a stopped wheel is not detected)");
  }
  const VehiclePhysics& v = config.vehicle_model;
  FailureDetection fd;
  FailureDetectorSettings& s = fd.detector;
  s.motors = config.motors();
  s.sources = read_sources(section);
  const HoverPoint hover = hover_point(config);
  fd.min_throttle = section.number(
      "min_throttle", hover.known ? kMinThrottleOfHover * hover.throttle : kMinThrottleFallback,
      0.0, 1.0);
  // A gate the hover stays below would keep the detector off for the whole
  // flight: refused, with the hover it must stay under.
  const auto below_hover = [&](MapReader& where, const char* key, double value, double at_hover,
                               const char* what) {
    if (!enabled || !hover.known || value < at_hover) return;
    std::ostringstream found, allowed;
    found << value;
    allowed << "below " << at_hover << ", the " << what
            << " at which the `vehicle:` section hovers (the detector judges nothing below it)";
    fail(where.path_of(key), found.str(), allowed.str());
  };
  below_hover(section, "min_throttle", fd.min_throttle, hover.throttle, "setpoint throttle");
  fd.motor_poles = static_cast<int>(section.number("motor_poles", 14, 2, 100));
  if (fd.motor_poles % 2 != 0) {
    fail(section.path_of("motor_poles"), std::to_string(fd.motor_poles),
         "an even number of magnet poles, 2 to 100");
  }
  s.time_constant_up_s = v.time_constant_up_s;
  s.time_constant_down_s = v.time_constant_down_s;

  MapReader telemetry = section.map("telemetry");
  s.telemetry_timeout_s = telemetry.number("timeout_ms", 100.0, 1.0, 10000.0) / 1e3;
  s.telemetry_persist_s = telemetry.number("persist_ms", 10.0, 0.0, 10000.0) / 1e3;
  s.telemetry_latency_s = telemetry.number("latency_ms", 20.0, 0.0, 100.0) / 1e3;
  s.rpm_ratio = telemetry.number("rpm_ratio", 0.7, 0.05, 0.95);
  s.rpm_high_ratio = telemetry.number("rpm_high_ratio", 1.25, 1.05, 5.0);
  s.current_ratio = telemetry.number("current_ratio", 0.4, 0.05, 0.95);
  s.load_ratio = telemetry.number("load_ratio", 0.6, 0.0, 0.95);
  s.min_reporting = static_cast<int>(telemetry.number("min_reporting", 3, 2, kMaxMotors));
  // A silent ESC is stopped on that alone only where the rest keep every
  // axis: six rotors or more. A quad gives up yaw and altitude for a motor
  // it stops, so a dead wire there must never look like a dead motor.
  s.silence_declares = s.motors >= kReallocatingRotors;
  s.min_motor_thrust = section.number(
      "min_motor_thrust",
      hover.known ? kMinMotorThrustOfHover * hover.thrust : kMinMotorThrustFallback, 0.0, 0.9);
  below_hover(section, "min_motor_thrust", s.min_motor_thrust, hover.thrust,
              "thrust fraction of each motor");
  telemetry.finish();

  MapReader rates = section.map("rates");
  const bool uses_rates = (s.sources & bit(DetectorSources::kRates)) != 0;
  if (uses_rates && enabled && !v.incomplete.empty()) {
    fail(section.path_of("sources"), "rates, with an incomplete vehicle section",
         "a complete `vehicle:` section for the rates source (" + v.incomplete + ")");
  }
  if (v.incomplete.empty() && !v.rotors.empty()) rates_scale(v, s);
  s.rates_timeout_s = rates.number("timeout_ms", 20.0, 1.0, 1000.0) / 1e3;
  // 15 Hz, or a quarter of the loop rate on slower loops.
  s.rates_filter_hz =
      rates.number("filter_hz", std::min(15.0, config.loop_rate_hz / 4.0), 0.5, 100.0);
  if (enabled && s.rates_filter_hz > config.loop_rate_hz / 4.0) {
    std::ostringstream found;
    found << s.rates_filter_hz << " with loop_rate_hz " << config.loop_rate_hz;
    fail(rates.path_of("filter_hz"), found.str(), "at most a quarter of loop_rate_hz");
  }
  s.rates_persist_s = rates.number("persist_ms", 60.0, 0.0, 10000.0) / 1e3;
  s.min_loss = rates.number("min_loss", 0.75, 0.1, 1.0);
  s.scale_time_constant_s = rates.number("scale_time_constant_s", 3.0, 0.1, 1000.0);
  s.max_off_axis = rates.number("max_off_axis", 0.3, 0.05, 2.0);
  s.min_residual_nm = rates.number("min_residual_nm", s.min_residual_nm, 0.0, 1000.0);
  rates.finish();

  MapReader outputs = section.map("outputs");
  if (enabled && (s.sources & bit(DetectorSources::kOutputs)) != 0 &&
      s.motors < kOutputsMinRotors) {
    std::ostringstream found;
    found << "outputs, on " << s.motors << " rotors";
    fail(section.path_of("sources"), found.str(),
         "the outputs source on 6 rotors or more (fewer do not outlive its second)");
  }
  s.outputs_filter_s = outputs.number("filter_s", 0.5, 0.01, 10.0);
  s.outputs_persist_s = outputs.number("persist_s", 1.0, 0.05, 10.0);
  s.outputs_high = outputs.number("high", 0.9, 0.5, 1.0);
  s.outputs_margin = outputs.number("margin", 0.35, 0.05, 1.0);
  outputs.finish();
  section.finish();
  if (enabled) config.failure_detection = fd;
}

}  // namespace motormix::config
