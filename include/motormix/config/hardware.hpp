#pragma once
// The `hardware:` section: what `motormix output` drives with the mixer's
// motor_pwm_t (docs/wiring-it-to-motors.md). Validated with the rest of the
// configuration; the output process refuses to start on any error.

#include <motormix/enum_names.hpp>
#include <string>
#include <vector>

namespace motormix::config {

enum class HardwareDriver {
  kNone,    // no output process (the default: motormix publishes motor_pwm_t only)
  kSerial,  // the pulse firmware on an ATmega328P (firmware/pulses) over a serial port
  kSysfs,   // Linux hardware PWM (/sys/class/pwm)
};

// What the pulse firmware puts on the ESC pins (serial driver only).
enum class EscProtocol {
  kPwm,       // servo pulses, min..max us at pulse_rate_hz
  kDshot150,  // DShot frames at pulse_rate_hz: throttle 48..2047 from min..max, 0 disarmed
  kDshot300,
  kDshot600,
};

inline constexpr EnumName<EscProtocol> kEscProtocolNames[] = {
    {EscProtocol::kPwm, "pwm"},
    {EscProtocol::kDshot150, "dshot150"},
    {EscProtocol::kDshot300, "dshot300"},
    {EscProtocol::kDshot600, "dshot600"},
};
inline const char* to_string(EscProtocol value) { return name_in(kEscProtocolNames, value); }

struct SerialPulses {
  std::string device;           // the microcontroller's serial port, e.g. /dev/ttyUSB0
  int baud = 250000;            // the firmware's rate
  double link_timeout_s = 0.1;  // the firmware disarms on its own after this silence
};

struct SysfsPwm {
  std::string root = "/sys/class/pwm";  // another root: a test tree, a chroot
  int chip = 0;                         // pwmchipN
  std::vector<int> channels;            // one PWM channel per motor, in motor order
};

// One ESC's KISS / BLHeli_32 telemetry wire.
struct TelemetryPort {
  std::string device;
  int baud = 115200;
  int motor = 0;  // 0-based motor index
};

struct Hardware {
  HardwareDriver driver = HardwareDriver::kNone;
  EscProtocol protocol = EscProtocol::kPwm;
  double pulse_rate_hz = 400.0;       // pulses (or DShot frames) per second on every channel
  bool bidirectional = false;         // DShot300/600: every ESC's eRPM back (esc_telemetry_t)
  double motor_pwm_timeout_s = 0.05;  // older motor_pwm_t: disarmed values
  SerialPulses serial;
  SysfsPwm sysfs;
  std::vector<TelemetryPort> telemetry;
};

inline constexpr EnumName<HardwareDriver> kHardwareDriverNames[] = {
    {HardwareDriver::kNone, "none"},
    {HardwareDriver::kSerial, "serial"},
    {HardwareDriver::kSysfs, "sysfs"},
};
inline const char* to_string(HardwareDriver value) { return name_in(kHardwareDriverNames, value); }

}  // namespace motormix::config
