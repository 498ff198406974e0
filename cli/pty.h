// A pseudo-terminal pair for hosting a simulated device: the simulator owns the master side,
// the gateway opens the slave path as if it were a serial port.
#pragma once

#include <string>
#include <system_error>

namespace drivegate {

class Pty {
 public:
  Pty() = default;
  ~Pty();
  Pty(const Pty&) = delete;
  Pty& operator=(const Pty&) = delete;

  // Creates the pair in raw mode. The slave side is held open too, so the master keeps working
  // while the gateway closes and reopens the path.
  std::error_code open();
  // Gives up ownership of the master descriptor (to an asio stream_descriptor).
  int release_master();
  [[nodiscard]] const std::string& slave_path() const { return slave_path_; }

 private:
  int master_ = -1;
  int slave_ = -1;
  std::string slave_path_;
};

}  // namespace drivegate
