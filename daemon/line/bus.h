// The bus engine: one serial line, the devices on it, one transaction at a time. See
// include/drivegate/driver.h for the contract it keeps with the drivers.
//
// Scheduling: devices with writes in flight go first, then every other device round-robin;
// a device that stopped answering is backed off (but still probed), and one exchange's attempts
// are capped by the device's time budget, so a dead or noisy device never starves the others.
// The port is reopened by itself, with back-off, when it fails or vanishes.
#pragma once

#include <spdlog/logger.h>

#include <boost/asio/io_context.hpp>
#include <boost/asio/serial_port.hpp>
#include <boost/asio/steady_timer.hpp>
#include <memory>
#include <optional>
#include <vector>

#include "config/config.h"
#include "gateway/device.h"

namespace drivegate {

class Bus : public std::enable_shared_from_this<Bus> {
 public:
  Bus(boost::asio::io_context& io, BusConfig config, std::vector<Device*> devices,
      std::shared_ptr<spdlog::logger> log);

  // Opens the port and starts polling; a started bus (one kept across a reload) stays as it is.
  void start();
  void stop();
  // Something new may be due (a write was queued): look now if the line is free.
  void kick();

  [[nodiscard]] const BusConfig& config() const { return config_; }
  [[nodiscard]] const BusCounters& counters() const { return counters_; }
  [[nodiscard]] bool is_open() const { return state_ != State::closed; }

 private:
  enum class State : std::uint8_t { closed, idle, gap, writing, awaiting_echo, awaiting_reply };

  void open_port();
  void port_failed(const std::string& what);
  void read_more();
  void on_bytes(std::size_t n);
  void advance();
  void process_rx(Device& dev);

  void pump();
  void begin(Device& dev, Exchange ex);
  void send_attempt();
  void on_written();
  void after_sent();
  void attempt_failed();
  void finish();
  void arm(std::chrono::steady_clock::duration after, void (Bus::*handler)());
  void on_reply_timeout();

  boost::asio::io_context& io_;
  BusConfig config_;
  std::vector<Device*> devices_;
  std::shared_ptr<spdlog::logger> log_;
  Device* streaming_ = nullptr;  // the device unsolicited bytes belong to, if any

  boost::asio::serial_port port_;
  boost::asio::steady_timer timer_;
  std::uint64_t timer_generation_ = 0;
  boost::asio::steady_timer reopen_timer_;
  Millis reopen_delay_{500};
  bool started_ = false;
  bool stopped_ = false;

  State state_ = State::closed;
  std::array<std::uint8_t, 512> chunk_{};
  Bytes rx_;
  Bytes tx_;    // the frame being written (owned here while asio writes it)
  Bytes echo_;  // bytes still expected back on a one-wire line
  bool echo_broken_ = false;
  Device* current_ = nullptr;
  std::optional<Exchange> exchange_;
  int attempt_ = 0;
  int max_attempts_ = 1;
  bool answered_ = false;        // the device sent something this exchange, if only a NACK
  std::size_t next_device_ = 0;  // round-robin position
  TimePoint last_activity_{};
  std::chrono::microseconds char_time_;
  BusCounters counters_;
};

}  // namespace drivegate
