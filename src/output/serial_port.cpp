// Only the kernel's termios2 here: <asm/termbits.h> and glibc's <termios.h>
// cannot be in one translation unit.
#include "output/serial_port.hpp"

#include <asm/termbits.h>
#include <fcntl.h>
#include <sys/ioctl.h>
#include <unistd.h>
#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace motormix::output {

int open_serial_port(const std::string& device, int baud) {
  const int fd = ::open(device.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    throw std::runtime_error("cannot open " + device + ": " + std::strerror(errno));
  }
  struct termios2 t {};
  if (ioctl(fd, TCGETS2, &t) != 0) {
    const std::string why = std::strerror(errno);
    ::close(fd);
    throw std::runtime_error(device + " is not a serial port: " + why);
  }
  t.c_iflag &= ~static_cast<tcflag_t>(IGNBRK | BRKINT | PARMRK | ISTRIP | INLCR | IGNCR | ICRNL |
                                      IXON | IXOFF | IXANY);
  t.c_oflag &= ~static_cast<tcflag_t>(OPOST);
  t.c_lflag &= ~static_cast<tcflag_t>(ECHO | ECHONL | ICANON | ISIG | IEXTEN);
  t.c_cflag &= ~static_cast<tcflag_t>(CSIZE | PARENB | CSTOPB | CRTSCTS | CBAUD);
  t.c_cflag |= CS8 | CLOCAL | CREAD | BOTHER;
  t.c_ispeed = static_cast<speed_t>(baud);
  t.c_ospeed = static_cast<speed_t>(baud);
  t.c_cc[VMIN] = 0;
  t.c_cc[VTIME] = 0;
  if (ioctl(fd, TCSETS2, &t) != 0) {
    const std::string why = std::strerror(errno);
    ::close(fd);
    throw std::runtime_error("cannot set " + device + " to " + std::to_string(baud) +
                             " baud, raw: " + why);
  }
  return fd;
}

}  // namespace motormix::output
