#include "pty.h"

#include <fcntl.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>

namespace drivegate {

Pty::~Pty() {
  if (master_ >= 0) ::close(master_);
  if (slave_ >= 0) ::close(slave_);
}

std::error_code Pty::open() {
  const auto fail = [this] {
    const std::error_code ec(errno, std::generic_category());
    if (master_ >= 0) ::close(master_);
    master_ = -1;
    return ec;
  };
  master_ = ::posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);
  if (master_ < 0) return fail();
  if (::grantpt(master_) != 0 || ::unlockpt(master_) != 0) return fail();
  char name[128];
  if (::ptsname_r(master_, name, sizeof name) != 0) return fail();
  slave_path_ = name;
  slave_ = ::open(name, O_RDWR | O_NOCTTY | O_CLOEXEC);
  if (slave_ < 0) return fail();
  // Raw both ways: no echo, no line discipline, no CR/LF translation, 8 bits.
  termios t{};
  if (::tcgetattr(slave_, &t) != 0) return fail();
  ::cfmakeraw(&t);
  if (::tcsetattr(slave_, TCSANOW, &t) != 0) return fail();
  return {};
}

int Pty::release_master() {
  const int fd = master_;
  master_ = -1;
  return fd;
}

}  // namespace drivegate
