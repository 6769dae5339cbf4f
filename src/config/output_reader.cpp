// output: (ranges, per-motor overrides, idle, slew), inputs:, channels:,
// motor_test: and realtime:.

#include "section_readers.hpp"

#include <cmath>
#include <sstream>

namespace motormix::config::reading {

namespace {

// Range, centre and disarmed value of one channel; shared by the defaults and
// the per-motor overrides.
void read_range(MapReader& map, OutputChannel& ch) {
  ch.min = map.number("min", ch.min, 0.0, kMaxOutputValue);
  ch.max = map.number("max", ch.max, 0.0, kMaxOutputValue);
  ch.center =
      map.number("center", ch.mode == OutputMode::kCentered ? (ch.min + ch.max) / 2 : ch.center,
                 0.0, kMaxOutputValue);
  ch.disarmed = map.number("disarmed", ch.disarmed, 0.0, kMaxOutputValue);
  if (!(ch.min < ch.max)) {
    std::ostringstream found;
    found << "min " << ch.min << " and max " << ch.max;
    fail(map.path_of("max"), found.str(), "max greater than min");
  }
  if (ch.mode == OutputMode::kCentered && !(ch.center > ch.min && ch.center < ch.max)) {
    std::ostringstream found;
    found << ch.center << " with min " << ch.min << " and max " << ch.max;
    fail(map.path_of("center"), found.str(), "a value strictly between min and max");
  }
}

}  // namespace

void read_output(MapReader output, Config& config) {
  const bool wheels = config.thrust_range() == ThrustRange::kBipolar;
  // Names through the table; which of them a vehicle takes follows its
  // thrust (rotors push one way, wheels both).
  const std::vector<std::string> allowed =
      wheels ? std::vector<std::string>{to_string(OutputMode::kCentered),
                                        to_string(OutputMode::kMagnitudeDirection)}
             : std::vector<std::string>{to_string(OutputMode::kUnipolar)};
  const OutputMode mode =
      *parse_in(kOutputModeNames, output.choice("mode", allowed.front(), allowed));
  OutputChannel ch;
  ch.mode = mode;
  if (mode == OutputMode::kCentered) {
    ch.disarmed = 1500.0;
  } else if (mode == OutputMode::kMagnitudeDirection) {
    ch.min = 0.0;
    ch.max = 255.0;
    ch.disarmed = 0.0;
  }
  config.output_unit =
      output.text("unit", ch.mode == OutputMode::kMagnitudeDirection ? "duty" : "us");
  read_range(output, ch);
  if (ch.mode == OutputMode::kUnipolar) {
    ch.idle = output.number("idle", 0.0, 0.0, 0.5);
    ch.thrust_model_factor = output.number("thrust_model_factor", 0.0, 0.0, 1.0);
  } else {
    for (const char* key : {"idle", "thrust_model_factor"}) {
      if (output.has(key))
        fail(output.path_of(key), "'" + std::string(key) + "' with mode " + to_string(mode),
             "only with mode unipolar");
      output.raw(key);
    }
  }
  ch.slew_per_s = output.number("slew_per_s", 0.0, 0.0, 1e9);
  // Aircraft spool up over half a second by default; wheels start at once.
  config.spool_up_s = output.number("spool_up_s", wheels ? 0.0 : 0.5, 0.0, 10.0);
  config.outputs.assign(static_cast<std::size_t>(config.motors()), ch);

  const YAML::Node per_motor = output.raw("per_motor");
  if (per_motor.IsDefined() && !per_motor.IsNull()) {
    const std::string path = output.path_of("per_motor");
    if (!per_motor.IsSequence() || static_cast<int>(per_motor.size()) != config.motors()) {
      fail(path, describe(per_motor),
           "a list of " + std::to_string(config.motors()) + " entries, one per motor");
    }
    for (std::size_t i = 0; i < per_motor.size(); ++i) {
      MapReader m(per_motor[i], path + "[" + std::to_string(i) + "]");
      OutputChannel& c = config.outputs[i];
      read_range(m, c);
      c.trim = m.number("trim", 0.0, -0.5, 0.5);
      c.reversed = read_bool(m, "reversed", false);
      m.finish();
    }
  }
  output.finish();
}

void read_inputs(MapReader inputs, Config& config) {
  config.inputs.yaw_source = inputs.choice("yaw_source", YawSource::kSetpoint, kYawSourceNames);
  config.inputs.setpoint_timeout_s =
      inputs.number("setpoint_timeout_ms", 100.0, 1.0, 10000.0) / 1e3;
  config.inputs.pid_timeout_s = inputs.number("pid_timeout_ms", 100.0, 1.0, 10000.0) / 1e3;
  config.inputs.failsafe = inputs.choice("failsafe", FailsafeAction::kDisarm, kFailsafeActionNames);
  config.inputs.hold_last_s = inputs.number("hold_last_ms", 500.0, 1.0, 5000.0) / 1e3;
  config.inputs.max_future_s = inputs.number("max_future_ms", 1000.0, 1.0, 3.6e6) / 1e3;
  config.inputs.arm_max_throttle = inputs.number("arm_max_throttle", 0.1, 0.0, 1.0);
  config.inputs.units = inputs.choice("units", InputUnits::kNormalized, kInputUnitsNames);
  inputs.finish();
}

void read_motor_test(MapReader test, Config& config) {
  config.motor_test.enabled = read_bool(test, "enabled", true);
  config.motor_test.max_throttle = test.number("max_throttle", 0.15, 0.0, 1.0);
  config.motor_test.max_seconds = test.number("max_seconds", 3.0, 0.0, 60.0);
  test.finish();
}

void read_realtime(MapReader rt, Config& config) {
  config.realtime.priority = static_cast<int>(rt.number("priority", 0, 0, 99));
  const YAML::Node cpus = rt.raw("cpus");
  if (cpus.IsDefined() && !cpus.IsNull()) {
    // An empty list, like no list, leaves the affinity alone.
    for (double c : read_numbers(cpus, rt.path_of("cpus"), 0, 1024, 0, 1023)) {
      config.realtime.cpus.push_back(static_cast<int>(c));
    }
  }
  config.realtime.lock_memory = read_bool(rt, "lock_memory", false);
  rt.finish();
}

void read_channels(MapReader channels, Config& config) {
  Channels& c = config.channels;
  c.setpoint = channels.text("setpoint", c.setpoint);
  c.pid = channels.text("pid", c.pid);
  c.motor_pwm = channels.text("motor_pwm", c.motor_pwm);
  c.status = channels.text("status", c.status);
  c.motor_status = channels.text("motor_status", c.motor_status);
  c.battery = channels.text("battery", c.battery);
  c.motor_test = channels.text("motor_test", c.motor_test);
  c.esc_telemetry = channels.text("esc_telemetry", c.esc_telemetry);
  c.attitude = channels.text("attitude", c.attitude);
  c.output_status = channels.text("output_status", c.output_status);
  c.esc_command = channels.text("esc_command", c.esc_command);
  c.lockstep = channels.text("lockstep", c.lockstep);
  channels.finish();
  // One channel, one message type: a shared input channel would hand each
  // message to two decoders (one of which rejects it, cycle after cycle),
  // and an output on an input's channel would feed the mixer its own
  // messages. Offline replay, reading each channel once, would behave
  // differently again.
  const std::pair<const char*, const std::string*> named[] = {
      {"setpoint", &c.setpoint},         {"pid", &c.pid},
      {"motor_pwm", &c.motor_pwm},       {"status", &c.status},
      {"motor_status", &c.motor_status}, {"battery", &c.battery},
      {"motor_test", &c.motor_test},     {"esc_telemetry", &c.esc_telemetry},
      {"attitude", &c.attitude},         {"output_status", &c.output_status},
      {"esc_command", &c.esc_command},   {"lockstep", &c.lockstep}};
  for (std::size_t i = 0; i < std::size(named); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      if (*named[i].second == *named[j].second) {
        fail(std::string("channels.") + named[i].first,
             "'" + *named[i].second + "', the channel of channels." + named[j].first,
             "a channel name no other input or output of this mixer uses");
      }
    }
  }
}

}  // namespace motormix::config::reading
