// Hosts an adapter's simulated devices on a pseudo-terminal (or a real serial port): feeds them
// the bytes the master sends, writes their replies after a turnaround, echoes the master's bytes
// on a simulated one-wire line, and passes operator lines to their control().
//
// Wire-timing mode makes a pty behave like the serial line it stands for: the line is
// half duplex, every byte occupies it for one character time (start bit, data bits, parity bit,
// stop bits at the configured baud), the master's bytes are taken to finish arriving one
// character time apart after they are read, and a reply starts one turnaround after the last
// byte of the request, its bytes written one at a time at their character times.
#pragma once

#include <boost/asio/io_context.hpp>
#include <boost/asio/posix/stream_descriptor.hpp>
#include <boost/asio/steady_timer.hpp>
#include <chrono>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "config/config.h"
#include "transport/port_lock.h"
#include "drivegate/adapter.h"
#include "pty.h"

namespace drivegate {

struct SimHostOptions {
  std::vector<std::uint32_t> addresses;        // one simulated device per address
  Options options;                             // the adapter's options, defaults filled in
  std::optional<BusConfig> port;               // a real line instead of a pty
  std::optional<std::filesystem::path> link;   // a symlink to the pty, for a stable path
  bool echo = false;                           // one-wire: the master hears itself
  std::chrono::microseconds turnaround{2000};  // device think time before a reply
  // Wire-timing mode: the time one character occupies the line (zero: off, bytes are instant).
  std::chrono::nanoseconds char_time{0};
  // Wire-timing mode: appends one line per event, times in steady-clock nanoseconds:
  //   rx ARRIVED ON_WIRE_END COUNT HEX   (a chunk from the master)
  //   tx FIRST_WRITTEN LAST_WRITTEN COUNT (a reply or stream frame, as paced onto the line)
  std::optional<std::filesystem::path> wire_log;
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
  void send(Bytes bytes, std::chrono::microseconds delay);
  // Wire-timing mode: queues bytes to go out from `earliest` on (or when the line is free).
  void transmit(Bytes bytes, TimePoint earliest);
  void pace();

  boost::asio::io_context& io_;
  const AdapterDescriptor& adapter_;
  SimHostOptions options_;
  std::vector<std::pair<std::uint32_t, std::unique_ptr<Simulator>>> sims_;
  Pty pty_;
  PortLock port_lock_;  // --port: the real line, held while simulating on it
  boost::asio::posix::stream_descriptor line_;
  boost::asio::steady_timer tick_;
  std::array<std::uint8_t, 512> chunk_{};
  bool running_ = false;
  std::string path_;
  // Wire-timing mode.
  struct Frame {
    Bytes bytes;
    TimePoint start;  // when its first byte begins on the line
    std::size_t written = 0;
    TimePoint first_written{};
  };
  std::deque<Frame> tx_queue_;
  boost::asio::steady_timer pace_;
  TimePoint line_free_{};  // the end of the last character on the line, either direction
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> log_{nullptr, &std::fclose};
};

}  // namespace drivegate
