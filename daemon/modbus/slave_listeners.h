// The daemon's Modbus RTU / ASCII listeners (docs/serial-listeners.md): on serial lines
// (modbus/serial_listener.h) and on TCP (modbus/rtu_tcp_listener.h), made from the [[listener]]
// tables whose framing is "rtu" or "ascii", reloaded in place when only their policy changed.
// The Modbus TCP (MBAP) listeners are modbus::Server's.
#pragma once

#include <spdlog/logger.h>

#include <boost/asio/io_context.hpp>
#include <memory>
#include <string>
#include <vector>

#include "config/config.h"
#include "modbus/backend.h"
#include "modbus/rtu_tcp_listener.h"
#include "modbus/serial_listener.h"

namespace drivegate {

class SlaveListeners {
 public:
  SlaveListeners(boost::asio::io_context& io, net::Clock& clock, modbus::Backend& backend,
                 modbus::DeviceIdentity identity, ServerConfig server,
                 std::shared_ptr<spdlog::logger> log);
  ~SlaveListeners();

  // Opens one for each RTU / ASCII listener in `listeners`. False (logged) when a TCP one cannot
  // listen; serial ports that cannot open yet are retried.
  bool start(const std::vector<ListenerConfig>& listeners);
  // The new policies (access, word order, write_reply, broadcast; allow and max_clients on TCP)
  // apply at once to the listeners in the same place (config/config_diff.h, same_place); one
  // added, removed or moved waits for the next restart (plan_reload names it).
  void reload(const std::vector<ListenerConfig>& listeners);
  void close();
  [[nodiscard]] const std::vector<std::shared_ptr<slave::SerialListener>>& serial() const {
    return serial_;
  }
  [[nodiscard]] const std::vector<std::shared_ptr<slave::RtuTcpListener>>& tcp() const {
    return tcp_;
  }

 private:
  boost::asio::io_context& io_;
  net::Clock& clock_;
  modbus::Backend& backend_;
  modbus::DeviceIdentity identity_;
  ServerConfig server_;
  std::shared_ptr<spdlog::logger> log_;
  std::vector<ListenerConfig> serial_configs_;
  std::vector<std::shared_ptr<slave::SerialListener>> serial_;
  std::vector<ListenerConfig> tcp_configs_;
  std::vector<std::shared_ptr<slave::RtuTcpListener>> tcp_;
};

}  // namespace drivegate
