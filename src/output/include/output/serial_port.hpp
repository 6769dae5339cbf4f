#pragma once
// A serial port in raw mode at any baud rate the driver takes (250000 for
// the pulse firmware is not one of the classic Bxxx constants: the kernel's
// termios2 with BOTHER sets it). Non-blocking.

#include <string>

namespace motormix::output {

// The open descriptor; throws std::runtime_error naming the device and the
// reason.
int open_serial_port(const std::string& device, int baud);

}  // namespace motormix::output
