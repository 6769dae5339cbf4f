// The `hardware:` section (documented in docs/wiring-it-to-motors.md).

#include "hardware_reader.hpp"

#include "motormix_link.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace motormix::config {

namespace {

std::string number_text(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// Every motor's output range and disarmed value must be a pulse of
// MM_LINK_MIN_PULSE_US..MM_LINK_MAX_PULSE_US that ends MM_LINK_MIN_LOW_US
// before the next period.
void check_outputs(const Config& config, const std::string& path, double period_us) {
  if (config.output_unit != "us") {
    fail("output.unit", config.output_unit, "us: the hardware drivers make pulses in microseconds");
  }
  const double longest = period_us - MM_LINK_MIN_LOW_US;
  for (std::size_t i = 0; i < config.outputs.size(); ++i) {
    const OutputChannel& ch = config.outputs[i];
    if (ch.mode == OutputMode::kMagnitudeDirection) {
      fail("output.mode", "magnitude_direction",
           "unipolar or centered: " + path + " makes servo pulses, not H-bridge duty");
    }
    for (double v : {ch.min, ch.max, ch.disarmed}) {
      if (v < MM_LINK_MIN_PULSE_US || v > std::min<double>(MM_LINK_MAX_PULSE_US, longest)) {
        std::ostringstream found, allowed;
        // pulse_rate_hz sits in hardware:, beside the driver's own section.
        found << "motor " << i + 1 << ": " << v << " us at hardware.pulse_rate_hz "
              << 1e6 / period_us << " (" << path << ")";
        allowed << MM_LINK_MIN_PULSE_US << ".." << std::min<double>(MM_LINK_MAX_PULSE_US, longest)
                << " us (a pulse ends " << MM_LINK_MIN_LOW_US << " us before the next period)";
        fail("output (min, max, disarmed)", found.str(), allowed.str());
      }
    }
  }
}

std::vector<int> read_channel_list(const YAML::Node& node, const std::string& path, int motors) {
  if (!node.IsSequence() || static_cast<int>(node.size()) != motors) {
    fail(path, describe(node),
         "a list of " + std::to_string(motors) + " PWM channel numbers, one per motor");
  }
  std::vector<int> out;
  for (std::size_t i = 0; i < node.size(); ++i) {
    const double v = to_number(node[i], path + "[" + std::to_string(i) + "]", 0, 1023);
    if (v != std::floor(v))
      fail(path + "[" + std::to_string(i) + "]", describe(node[i]), "an integer");
    for (int seen : out) {
      if (seen == static_cast<int>(v)) {
        fail(path + "[" + std::to_string(i) + "]", describe(node[i]),
             "a channel no other motor uses");
      }
    }
    out.push_back(static_cast<int>(v));
  }
  return out;
}

int integer(MapReader& m, const std::string& key, double fallback, double lo, double hi) {
  const double v = m.number(key, fallback, lo, hi);
  if (v != std::floor(v)) fail(m.path_of(key), number_text(v), "an integer");
  return static_cast<int>(v);
}

}  // namespace

void read_hardware(MapReader section, Config& config) {
  Hardware hw;
  hw.driver = section.choice("driver", HardwareDriver::kNone, kHardwareDriverNames);
  hw.protocol = section.choice("protocol", EscProtocol::kPwm, kEscProtocolNames);
  const bool dshot = hw.protocol != EscProtocol::kPwm;
  hw.bidirectional = section.boolean("bidirectional", false);
  if (hw.bidirectional && hw.protocol != EscProtocol::kDshot300 &&
      hw.protocol != EscProtocol::kDshot600) {
    fail(section.path_of("bidirectional"),
         "true with protocol " + std::string(to_string(hw.protocol)),
         "false, or protocol dshot300 / dshot600 (the replies of DShot150 outlast the firmware's "
         "window)");
  }
  if (hw.bidirectional && config.motors() > static_cast<int>(MM_LINK_MAX_BIDIR_CHANNELS)) {
    fail(section.path_of("bidirectional"),
         "true with " + std::to_string(config.motors()) + " motors",
         "at most " + std::to_string(MM_LINK_MAX_BIDIR_CHANNELS) +
             " motors (the firmware reads replies on pins D2..D5)");
  }
  // DShot frames are short (27-107 us): up to 4 kHz; servo pulses up to 500
  // Hz; with replies to decode after each frame, 1 kHz.
  const double max_rate_hz = 1e6 / (hw.bidirectional ? MM_LINK_MIN_BIDIR_PERIOD_US
                                    : dshot          ? MM_LINK_MIN_DSHOT_PERIOD_US
                                                     : MM_LINK_MIN_PERIOD_US);
  hw.pulse_rate_hz = section.number("pulse_rate_hz", dshot ? std::min(1000.0, max_rate_hz) : 400.0,
                                    1e6 / MM_LINK_MAX_PERIOD_US, max_rate_hz);
  if (dshot && hw.driver != HardwareDriver::kSerial) {
    fail(section.path_of("protocol"),
         std::string(to_string(hw.protocol)) + " with driver " + to_string(hw.driver),
         "pwm: only the serial driver (the pulse firmware) speaks DShot");
  }
  if (dshot && config.motors() > static_cast<int>(MM_LINK_MAX_DSHOT_CHANNELS)) {
    fail(section.path_of("protocol"),
         std::string(to_string(hw.protocol)) + " with " + std::to_string(config.motors()) +
             " motors",
         "at most " + std::to_string(MM_LINK_MAX_DSHOT_CHANNELS) +
             " motors (DShot frames every channel of port D at once: pins D2..D7)");
  }
  if (dshot) {
    for (const OutputChannel& ch : config.outputs) {
      if (ch.mode != OutputMode::kUnipolar) {
        fail("output.mode", to_string(ch.mode),
             "unipolar with hardware.protocol " + std::string(to_string(hw.protocol)) +
                 " (3D DShot is not supported)");
      }
    }
  }
  hw.motor_pwm_timeout_s = section.number("motor_pwm_timeout_ms", 50.0, 5.0, 1000.0) / 1e3;

  MapReader serial = section.map("serial");
  if (hw.driver == HardwareDriver::kSerial && !serial.has("device")) {
    fail(section.path_of("serial") + ".device", "nothing",
         "the microcontroller's serial port (driver: serial)");
  }
  hw.serial.device = serial.text("device", "");
  hw.serial.baud = integer(serial, "baud", 250000, 9600, 2000000);
  hw.serial.link_timeout_s =
      serial.number("link_timeout_ms", 100.0, MM_LINK_MIN_TIMEOUT_MS, MM_LINK_MAX_TIMEOUT_MS) / 1e3;
  serial.finish();
  if (hw.driver == HardwareDriver::kSerial &&
      config.motors() > static_cast<int>(MM_LINK_MAX_CHANNELS)) {
    fail(
        section.path_of("driver"), "serial with " + std::to_string(config.motors()) + " motors",
        "at most " + std::to_string(MM_LINK_MAX_CHANNELS) + " motors (the firmware's pins D2..D9)");
  }

  MapReader sysfs = section.map("sysfs");
  hw.sysfs.root = sysfs.text("root", "/sys/class/pwm");
  hw.sysfs.chip = integer(sysfs, "chip", 0, 0, 1023);
  const YAML::Node channels = sysfs.raw("channels");
  if (channels.IsDefined() && !channels.IsNull()) {
    hw.sysfs.channels = read_channel_list(channels, sysfs.path_of("channels"), config.motors());
  } else if (hw.driver == HardwareDriver::kSysfs) {
    for (int i = 0; i < config.motors(); ++i) hw.sysfs.channels.push_back(i);
  }
  sysfs.finish();

  const YAML::Node telemetry = section.raw("telemetry");
  if (telemetry.IsDefined() && !telemetry.IsNull()) {
    const std::string path = section.path_of("telemetry");
    if (!telemetry.IsSequence()) fail(path, describe(telemetry), "a list of {device, motor, baud}");
    for (std::size_t i = 0; i < telemetry.size(); ++i) {
      MapReader entry(telemetry[i], path + "[" + std::to_string(i) + "]");
      TelemetryPort port;
      if (!entry.has("device"))
        fail(entry.path_of("device"), "nothing", "the ESC telemetry wire's serial port");
      port.device = entry.text("device", "");
      port.baud = integer(entry, "baud", 115200, 9600, 2000000);
      port.motor = integer(entry, "motor", 0, 1, config.motors()) - 1;
      entry.finish();
      hw.telemetry.push_back(port);
    }
    // A KISS / BLHeli_32 ESC sends its telemetry frame only when a DShot
    // frame's telemetry bit asks for one: with servo PWM nothing asks, and
    // the wire would never hear a byte.
    if (!hw.telemetry.empty() && !dshot) {
      fail(path,
           std::to_string(hw.telemetry.size()) + " KISS telemetry wire(s) with protocol " +
               to_string(hw.protocol),
           "a DShot protocol (dshot150, dshot300 or dshot600 with driver serial): a KISS ESC "
           "answers only a DShot frame whose telemetry bit asks, and servo PWM cannot ask "
           "(docs/wiring-it-to-motors.md)");
    }
  }
  section.finish();

  if (hw.driver != HardwareDriver::kNone) {
    // DShot carries min..max as a throttle: no pulse has to fit in a frame period.
    check_outputs(config, section.path_of(to_string(hw.driver)),
                  dshot ? MM_LINK_MAX_PERIOD_US : 1e6 / hw.pulse_rate_hz);
    if (hw.driver == HardwareDriver::kSerial && hw.serial.link_timeout_s < 2.0 / hw.pulse_rate_hz) {
      fail(section.path_of("serial") + ".link_timeout_ms",
           number_text(hw.serial.link_timeout_s * 1e3), "at least two pulse periods");
    }
  }
  config.hardware = hw;
}

}  // namespace motormix::config
