// The northbound Modbus TCP server: an acceptor on host:port and one Connection per client, all
// on the caller's io_context (single-threaded; nothing here blocks). Requests are dispatched
// against a Backend; see backend.h for the contract.
#pragma once

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <memory>
#include <system_error>

#include "backend.h"
#include "server_options.h"

namespace spdlog {
class logger;
}

namespace drivegate::modbus {

struct ServerState;

class Server {
 public:
  // `backend` must outlive the io_context's processing of this server's handlers.
  Server(boost::asio::io_context& io, Backend& backend, ServerOptions options,
         std::shared_ptr<spdlog::logger> log);
  ~Server();  // close()
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  // Binds, listens and starts accepting. Errors: the address does not parse, or the system's.
  std::error_code listen();
  // The bound endpoint (and port, useful with port 0) once listen() succeeded.
  boost::asio::ip::tcp::endpoint local_endpoint() const;
  std::uint16_t port() const { return local_endpoint().port(); }

  const ServerStats& stats() const;
  std::size_t client_count() const;

  // Stops accepting and closes every connection. Replies to pending writes are dropped. Once the
  // backend has called every pending `done`, nothing of this server is left on the io_context.
  void close();

 private:
  std::shared_ptr<ServerState> state_;
};

}  // namespace drivegate::modbus
