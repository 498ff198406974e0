// Hosts an adapter's simulated devices on a pseudo-terminal (or a real serial port): feeds them
// the bytes the master sends, writes their replies after a turnaround, echoes the master's bytes
// on a simulated one-wire line, and passes operator lines to their control().
#pragma once

#include <boost/asio/io_context.hpp>
#include <boost/asio/posix/stream_descriptor.hpp>
#include <boost/asio/steady_timer.hpp>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/config.h"
#include "drivegate/adapter.h"
#include "pty.h"

namespace drivegate {

struct SimHostOptions {
  std::vector<std::uint32_t> addresses;          // one simulated device per address
  Options options;                               // the adapter's options, defaults filled in
  std::optional<BusConfig> port;                 // a real line instead of a pty
  std::optional<std::filesystem::path> link;     // a symlink to the pty, for a stable path
  bool echo = false;                             // one-wire: the master hears itself
  Millis turnaround{2};                          // device think time before a reply
};

class SimHost {
 public:
  SimHost(boost::asio::io_context& io, const AdapterDescriptor& adapter, SimHostOptions options);
  ~SimHost();
  SimHost(const SimHost&) = delete;
  SimHost& operator=(const SimHost&) = delete;

  // Creates the simulators and the line. Returns a one-line reason on failure.
  std::string open();
  void start();
  void stop();
  [[nodiscard]] std::string path() const;
  // An operator line: "CMD ..." goes to every simulated device, "@ADDR CMD ..." to one.
  std::string control(const std::string& line);

 private:
  void read_more();
  void tick();
  void send(Bytes bytes, Millis delay);

  boost::asio::io_context& io_;
  const AdapterDescriptor& adapter_;
  SimHostOptions options_;
  std::vector<std::pair<std::uint32_t, std::unique_ptr<Simulator>>> sims_;
  Pty pty_;
  boost::asio::posix::stream_descriptor line_;
  boost::asio::steady_timer tick_;
  std::array<std::uint8_t, 512> chunk_{};
  bool running_ = false;
  std::string path_;
};

}  // namespace drivegate
