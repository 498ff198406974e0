// RTU (or ASCII) frames over TCP: the "Modbus RTU over TCP" many SCADA drivers speak to serial
// device servers, CRC and all, on a socket. A listening address (the one acceptor every server
// shares, net/acceptor.h: allow list, max_clients), and one SlaveHost per client, its frames
// delimited by their length (no line timing on a socket). Each client is its own master: its
// session names it in the audit trail; the listener's counters are shared by its clients.
#pragma once

#include <spdlog/logger.h>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <chrono>
#include <memory>
#include <string>
#include <unordered_set>

#include "net/acceptor.h"
#include "net/allow_list.h"
#include "slave_host.h"

namespace drivegate::slave {

struct RtuTcpOptions {
  std::string host = "*";
  std::uint16_t port = 0;
  net::AllowList allow;
  std::size_t max_clients = 32;
  std::chrono::milliseconds idle_timeout{60'000};  // no request for this long closes; 0 = off
  std::chrono::milliseconds frame_timeout{2'000};  // a partial frame older than this closes
  modbus_serial::Framing framing = modbus_serial::Framing::rtu;
  modbus::DeviceIdentity identity;
};

class RtuTcpListener : public std::enable_shared_from_this<RtuTcpListener> {
 public:
  RtuTcpListener(boost::asio::io_context& io, net::Clock& clock, modbus::Backend& backend,
                 RtuTcpOptions options, std::shared_ptr<const SlavePolicy> policy,
                 std::shared_ptr<spdlog::logger> log);
  ~RtuTcpListener();
  RtuTcpListener(const RtuTcpListener&) = delete;
  RtuTcpListener& operator=(const RtuTcpListener&) = delete;

  // Binds and starts accepting; an error leaves nothing open.
  std::error_code listen();
  void close();
  // New access, word order, write_reply, broadcast for every client; allow list and max_clients.
  void set_policy(std::shared_ptr<const SlavePolicy> policy, net::AllowList allow,
                  std::size_t max_clients);

  [[nodiscard]] const std::string& name() const { return name_; }
  [[nodiscard]] const RtuTcpOptions& options() const { return options_; }
  [[nodiscard]] const SlavePolicy& policy() const { return *policy_; }
  [[nodiscard]] const modbus::SerialCounters& counters() const { return counters_.counts; }
  [[nodiscard]] std::uint16_t port() const;
  [[nodiscard]] std::size_t clients() const { return clients_.size(); }
  [[nodiscard]] std::uint64_t bytes_received() const { return bytes_received_; }
  [[nodiscard]] const net::AcceptStats& accept_stats() const { return acceptor_->stats(); }

 private:
  class Client;
  std::shared_ptr<const SlavePolicy> client_policy(const std::string& peer) const;

  boost::asio::io_context& io_;
  net::Clock& clock_;
  modbus::Backend& backend_;
  RtuTcpOptions options_;
  std::shared_ptr<const SlavePolicy> policy_;
  std::shared_ptr<spdlog::logger> log_;
  std::string name_;  // "0.0.0.0:4001 (rtu over tcp)"
  std::shared_ptr<net::Acceptor> acceptor_;
  LineCounters counters_;
  std::unordered_set<std::shared_ptr<Client>> clients_;
  std::uint64_t bytes_received_ = 0;
  bool closed_ = false;
};

}  // namespace drivegate::slave
