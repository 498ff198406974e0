// A loopback TCP port for a child process to listen on, which no other test takes meanwhile.
//
// A port bound to 0 and released comes from the kernel's ephemeral range, the range an outgoing
// connection's local port is also drawn from: under `ctest -j`, a client connecting elsewhere can
// take it before the child binds it (CI saw "cannot listen on 127.0.0.1:44271: Address already in
// use"), and two test processes can be handed the same one. So a port is taken below the
// ephemeral range, where no outgoing connection lands, and claimed with an flock on a file named
// after it, held until the test process exits: another test process skips a claimed port, and
// one process never gets the same port twice.
#pragma once

#include <fcntl.h>
#include <netinet/in.h>
#include <sys/file.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdint>
#include <fstream>
#include <random>
#include <stdexcept>
#include <string>

#include "loopback.h"

namespace drivegate::test {

namespace free_port_detail {

// The first port of the kernel's ephemeral range (Linux's default when it cannot be read).
inline int ephemeral_low() {
  int low = 32768;
  int high = 60999;
  std::ifstream("/proc/sys/net/ipv4/ip_local_port_range") >> low >> high;
  return low;
}

// True when `port` can be bound on loopback now (nothing else on the machine holds it).
inline bool bindable(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return false;
  const sockaddr_in a = loopback(port);
  const bool ok = ::bind(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a) == 0;
  ::close(fd);
  return ok;
}

// Claims `port` for this process: an flock on /tmp/drivegate-test-ports/<port>, whose descriptor
// is left open on purpose (the claim ends when the process does). False if another holds it.
inline bool claim(int port) {
  const std::string dir = "/tmp/drivegate-test-ports";
  if (::mkdir(dir.c_str(), 01777) == 0) ::chmod(dir.c_str(), 01777);  // past the umask
  const std::string file = dir + "/" + std::to_string(port);
  const int fd = ::open(file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
  if (fd < 0) return false;
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    ::close(fd);
    return false;
  }
  return true;
}

}  // namespace free_port_detail

// A TCP port nobody listens on, below the ephemeral range and claimed for this test process.
inline int free_port() {
  const int high = free_port_detail::ephemeral_low() - 1;
  const int low = high > 20000 ? high - 12000 : 1024;
  std::random_device seed;
  std::mt19937 pick(seed());
  std::uniform_int_distribution<int> in_range(low, high);
  for (int attempt = 0; attempt < 1000; ++attempt) {
    const int port = in_range(pick);
    if (free_port_detail::claim(port) && free_port_detail::bindable(port)) return port;
  }
  throw std::runtime_error("no free TCP port below the ephemeral range");
}

}  // namespace drivegate::test
