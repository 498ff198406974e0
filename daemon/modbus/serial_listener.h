// A serial listener: drivegate as a Modbus RTU / ASCII slave on a line a master owns (a PLC's
// RS-485 port, a DCS serial card, a BMS). The line is a bus's kind of port (a tty, or a serial
// device server's tcp:// / rfc2217://, transport/transport.h), owned exclusively as a bus's is,
// reopened with back-off when it goes (an unplugged USB adapter), logged once per outage. What
// arrives on it is served by one SlaveHost.
#pragma once

#include <spdlog/logger.h>

#include <boost/asio/io_context.hpp>
#include <chrono>
#include <memory>
#include <string>

#include "config/config.h"
#include "slave_host.h"
#include "transport/transport.h"

namespace drivegate::slave {

struct SerialListenerOptions {
  BusConfig line;  // port, baud, parity, data / stop bits, rs485, reopen_max; name for the log
  modbus_serial::Framing framing = modbus_serial::Framing::rtu;
  std::chrono::milliseconds ascii_timeout{1000};  // Serial Line 2.5.2.1
  std::chrono::milliseconds latency{20};          // modbus::LineTiming::latency
  modbus::DeviceIdentity identity;
};

class SerialListener : public std::enable_shared_from_this<SerialListener> {
 public:
  SerialListener(boost::asio::io_context& io, net::Clock& clock, modbus::Backend& backend,
                 SerialListenerOptions options, std::shared_ptr<const SlavePolicy> policy,
                 std::shared_ptr<spdlog::logger> log);
  ~SerialListener();
  SerialListener(const SerialListener&) = delete;
  SerialListener& operator=(const SerialListener&) = delete;

  void start();
  void close();
  void set_policy(std::shared_ptr<const SlavePolicy> policy);

  [[nodiscard]] const std::string& name() const { return name_; }
  [[nodiscard]] const SerialListenerOptions& options() const { return options_; }
  [[nodiscard]] const SlavePolicy& policy() const { return *policy_; }
  [[nodiscard]] const modbus::SerialCounters& counters() const { return counters_.counts; }
  [[nodiscard]] bool open() const { return open_; }
  [[nodiscard]] std::uint64_t bytes_received() const { return bytes_received_; }
  [[nodiscard]] std::uint64_t reopens() const { return reopens_; }

 private:
  void try_open();
  void on_open(std::error_code ec);
  void read();
  void on_read(std::error_code ec, ByteView data);
  void send(Bytes frame);
  void lost(std::error_code ec, const char* what);
  void retry_later();

  SerialListenerOptions options_;
  std::shared_ptr<const SlavePolicy> policy_;
  std::shared_ptr<spdlog::logger> log_;
  std::string name_;  // "serial /dev/ttyS1 (rtu)"
  std::unique_ptr<Transport> transport_;
  LineCounters counters_;
  std::shared_ptr<SlaveHost> host_;
  net::Timer retry_;
  std::chrono::milliseconds backoff_{100};
  bool open_ = false;
  bool outage_logged_ = false;
  bool closed_ = false;
  bool writing_ = false;
  Bytes tx_queue_;  // frames waiting while one is written (at most a reply or two)
  // A line that echoes what we send (`echo`, a one-wire or an RS-485 adapter that hears itself):
  // the bytes of our replies still to come back, dropped as they do.
  Bytes echo_;
  std::uint64_t bytes_received_ = 0;
  std::uint64_t reopens_ = 0;
  // Every pending transport callback holds this; close() clears it so they find nothing.
  std::shared_ptr<bool> alive_ = std::make_shared<bool>(true);
};

}  // namespace drivegate::slave
