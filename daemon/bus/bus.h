// One serial line on the daemon's io_context: the Asio wiring of a BusEngine. It owns the
// transport (a local port or a serial device server: opened, configured, and reopened with
// back-off when it fails or vanishes), the engine's alarm timer and the read loop; the engine
// decides everything else. Nothing here knows a protocol.
#pragma once

#include <spdlog/logger.h>

#include <array>
#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>
#include <memory>
#include <vector>

#include "bus/bus_engine.h"
#include "config/config.h"
#include "transport/transport.h"

namespace drivegate {

class Bus final : public std::enable_shared_from_this<Bus>, private BusClock, private BusLine {
 public:
  Bus(boost::asio::io_context& io, BusConfig config, std::vector<Station*> stations,
      std::shared_ptr<spdlog::logger> log);

  // Opens the port and starts polling; a started bus (one kept across a reload) stays as it is.
  void start();
  void stop();

  // A capture's tap on this line (bus/frame_tap.h); removed before it goes.
  void add_tap(FrameTap* tap) { engine_.add_tap(tap); }
  void remove_tap(FrameTap* tap) { engine_.remove_tap(tap); }
  [[nodiscard]] const std::vector<Station*>& stations() const { return engine_.stations(); }
  // A reload changed the devices on this line, not its settings: the port stays open.
  void replace_stations(std::vector<Station*> stations) {
    engine_.replace_stations(std::move(stations));
  }

  [[nodiscard]] const BusConfig& config() const { return config_; }
  [[nodiscard]] const BusCounters& counters() const { return engine_.counters(); }
  [[nodiscard]] bool is_open() const { return open_; }

 private:
  // BusClock
  [[nodiscard]] TimePoint now() const override { return Clock::now(); }
  void set_alarm(TimePoint at) override;
  // BusLine
  void send(ByteView frame) override;

  void open_port();
  void port_opened(std::error_code ec);
  void schedule_reopen();
  void port_failed(const std::string& what);
  void read_more();
  void check_silence();

  BusConfig config_;
  std::shared_ptr<spdlog::logger> log_;
  BusEngine engine_;
  std::unique_ptr<Transport> transport_;
  boost::asio::steady_timer alarm_;
  std::uint64_t alarm_generation_ = 0;
  boost::asio::steady_timer reopen_timer_;
  Millis reopen_delay_;
  bool started_ = false;
  bool stopped_ = false;
  bool open_ = false;
  bool opening_ = false;
  bool ever_open_ = false;
  bool open_failure_logged_ = false;  // this outage's "cannot open" is in the log
  // A device server can hang with its TCP connection up: when every device has gone silent and
  // nothing came for the longest comm timeout, a network bus reconnects.
  boost::asio::steady_timer silence_timer_;
  TimePoint last_heard_{};
};

}  // namespace drivegate
