// Baud rates through the Linux termios2 interface. Kept in its own file: <asm/termbits.h>
// cannot be included together with <termios.h>.
#include <asm/termbits.h>
#include <sys/ioctl.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>

#include "edvs/transport.h"

namespace edvs {

bool setSerialBaudRate(int fd, int baud) {
  if (baud <= 0) return false;
  struct termios2 tio;
  if (ioctl(fd, TCGETS2, &tio) != 0) return false;
  // BOTHER with an explicit speed covers standard and non-standard rates alike; the kernel
  // maps a standard one back to its constant.
  tio.c_cflag &= ~static_cast<tcflag_t>(CBAUD);
  tio.c_cflag |= BOTHER;
  tio.c_ispeed = static_cast<speed_t>(baud);
  tio.c_ospeed = static_cast<speed_t>(baud);
  if (ioctl(fd, TCSETS2, &tio) != 0) return false;
  struct termios2 check;
  if (ioctl(fd, TCGETS2, &check) != 0) return false;
  // Drivers that cannot run the rate either fail above or silently pick another one.
  const double ratio = static_cast<double>(check.c_ospeed) / baud;
  return ratio > 0.97 && ratio < 1.03;
}

int serialBaudRate(int fd) {
  struct termios2 tio;
  if (ioctl(fd, TCGETS2, &tio) != 0) {
    throw std::runtime_error(std::string("TCGETS2 failed: ") + std::strerror(errno));
  }
  return static_cast<int>(tio.c_ospeed);
}

}  // namespace edvs
