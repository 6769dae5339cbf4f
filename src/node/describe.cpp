#include "node/describe.hpp"

#include <motormix/config/hover_point.hpp>
#include <motormix/config/security.hpp>

#include <iomanip>
#include <optional>
#include <sstream>

namespace motormix::node {

std::vector<std::string> describe_run(const config::Config& c, const loop::ControlLoop& loop) {
  std::vector<std::string> lines;
  std::ostringstream s;
  s << "vehicle '" << c.name << "', " << c.motors() << " motors (" << c.description()
    << "), strategy " << to_string(c.strategy);
  lines.push_back(s.str());
  s.str("");
  s << "inputs '" << c.channels.setpoint << "' (setpoint, timeout "
    << c.inputs.setpoint_timeout_s * 1e3 << " ms), '" << c.channels.pid << "' (pid, timeout "
    << c.inputs.pid_timeout_s * 1e3 << " ms), yaw from " << to_string(c.inputs.yaw_source);
  lines.push_back(s.str());
  // The inputs' scale through this vehicle's physics: what one unit of each
  // demand is, or (inputs.units: physical) what the newtons become.
  std::optional<loop::PhysicalInputs> built;
  const loop::PhysicalInputs* scale = loop.physical_inputs();
  if (!scale && (built = loop::PhysicalInputs::build(c, loop.mixer()))) scale = &*built;
  if (scale) {
    const Eigen::Matrix3d& m = scale->torque_per_demand();
    s.str("");
    s << "inputs in "
      << (loop.physical_inputs() ? "newtons and newton-metres (inputs.units physical)"
                                 : "demands (inputs.units normalized)")
      << std::setprecision(4) << ": throttle 1 = " << scale->thrust_at_full_n() << " N, hover "
      << scale->hover_thrust_n() << " N at throttle " << scale->hover_throttle()
      << "; one unit of roll, pitch, yaw = " << m(0, 0) << ", " << m(1, 1) << ", " << m(2, 2)
      << " N m at hover";
    lines.push_back(s.str());
  }
  s.str("");
  s << "outputs '" << c.channels.motor_pwm << "' at " << c.loop_rate_hz << " Hz, status '"
    << c.channels.status << "' at " << c.status_rate_hz << " Hz";
  lines.push_back(s.str());
  if (const loop::DetectionRunner* runner = loop.detection()) {
    const FailureDetectorSettings& d = runner->detector().settings();
    const auto uses = [&d](DetectorSources source) {
      return (d.sources & static_cast<std::uint8_t>(source)) != 0;
    };
    s.str("");
    s << "failure detection:";
    if (uses(DetectorSources::kTelemetry)) s << " telemetry (" << c.channels.esc_telemetry << ")";
    if (uses(DetectorSources::kRates)) s << " rates (" << c.channels.attitude << ")";
    if (uses(DetectorSources::kOutputs)) s << " outputs";
    // The gates, beside the hover they are fractions of: a reader sees at
    // once whether detection runs in hover.
    const config::HoverPoint hover = config::hover_point(c);
    s << "; judges from throttle " << runner->min_throttle() << " and motor thrust "
      << d.min_motor_thrust;
    if (hover.known) {
      s << " (hover: throttle " << hover.throttle << ", motor thrust " << hover.thrust << ")";
    } else {
      s << " (fixed defaults: no `vehicle:` mass and thrust to find the hover)";
    }
    lines.push_back(s.str());
  }
  if (!c.motor_loss_summary().empty()) lines.push_back(c.motor_loss_summary());
  lines.push_back(config::describe(c.security));
  return lines;
}

}  // namespace motormix::node
