#pragma once
// Whether `motormix output` may pass a DShot special command (esc_command_t)
// to the firmware: DShot configured, the command in range, and every output
// disarmed. Pure: the caller says what the gate and the last write were.

#include <motormix/config/hardware.hpp>

#include <cstdint>
#include <iosfwd>

namespace motormix::output {

inline constexpr int kMaxCommandRepeat = 100;

struct EscCommandRequest {
  int command = 0;           // 1..47
  int repeat = 0;            // 1..kMaxCommandRepeat
  std::uint32_t motors = 0;  // bit i: output i
};

// Why the command is refused, or nullptr when it may go to the driver.
// `outputs`: the configured count; `disarmed`: the gate's state and the
// last write both disarmed.
const char* esc_command_refusal(config::EscProtocol protocol, const EscCommandRequest& request,
                                int outputs, bool disarmed);

// The log's line for each command, at most four a second: a flood of
// commands on the bus must not flood the log (the counts carry every one).
class EscCommandLog {
 public:
  void line(std::ostream& log, double now_s, const EscCommandRequest& request, const char* why);

 private:
  static constexpr double kIntervalS = 0.25;
  double last_s_ = -1e9;
  std::uint64_t unlogged_ = 0;
};

}  // namespace motormix::output
