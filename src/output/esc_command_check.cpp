#include "output/esc_command_check.hpp"

#include "motormix_link.h"

#include <ostream>

namespace motormix::output {

const char* esc_command_refusal(config::EscProtocol protocol, const EscCommandRequest& r,
                                int outputs, bool disarmed) {
  if (protocol == config::EscProtocol::kPwm)
    return "hardware.protocol is pwm (special commands are DShot's)";
  if (r.command < 1 || r.command > static_cast<int>(MM_LINK_DSHOT_MAX_COMMAND) || r.repeat < 1 ||
      r.repeat > kMaxCommandRepeat || r.motors == 0 || (r.motors >> outputs) != 0)
    return "out of range (command 1..47, repeat 1..100, motors of this configuration)";
  if (!disarmed) return "an output is armed";
  return nullptr;
}

void EscCommandLog::line(std::ostream& log, double now_s, const EscCommandRequest& r,
                         const char* why) {
  if (now_s - last_s_ < kIntervalS) {
    ++unlogged_;
    return;
  }
  last_s_ = now_s;
  log << "motormix output: ESC command " << r.command;
  if (why != nullptr) {
    log << " refused: " << why;
  } else {
    log << " sent to motors 0x" << std::hex << r.motors << std::dec << " in " << r.repeat
        << " frames";
  }
  if (unlogged_ > 0) log << " (" << unlogged_ << " more since the last line)";
  unlogged_ = 0;
  log << std::endl;
}

}  // namespace motormix::output
