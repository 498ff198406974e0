#include "http_server.h"

#include <spdlog/spdlog.h>

#include <vector>

#include "http_connection.h"

namespace drivegate::http {

namespace asio = boost::asio;
using asio::ip::tcp;

namespace {

// The status page's rule for a client its allow list let through: a slot of max_clients
// (captures have their own, HttpOptions::max_captures).
net::Admission admit(const HttpState& state) {
  return state.live.size() - state.capturing < state.options.max_clients ? net::Admission::take
                                                                         : net::Admission::refuse;
}

}  // namespace

HttpServer::HttpServer(asio::io_context& io, net::Clock& clock, Content& content,
                       HttpOptions options, std::shared_ptr<spdlog::logger> log)
    : state_(std::make_shared<HttpState>(io, clock, content, std::move(options), std::move(log))) {}

HttpServer::~HttpServer() {
  close();
}

std::error_code HttpServer::listen() {
  // Every interface here is every IPv4 one (the status page is for the plant's network).
  if (const auto ec = state_->acceptor->bind(state_->options.host, state_->options.port,
                                             asio::socket_base::max_listen_connections,
                                             net::AnyAddress::ipv4)) {
    return ec;
  }
  state_->log->info("http: status page, /api/v1/status and /metrics on http://{}:{}/",
                    state_->acceptor->local_endpoint().address().to_string(), port());
  const std::shared_ptr<HttpState> state = state_;
  state_->acceptor->start([state](const asio::ip::address&) { return admit(*state); },
                          [state](tcp::socket socket) {
                            std::make_shared<HttpConnection>(state, std::move(socket))->start();
                          });
  return {};
}

std::uint16_t HttpServer::port() const {
  return state_->acceptor->local_endpoint().port();
}

void HttpServer::close() {
  if (state_->closed) return;
  state_->closed = true;
  state_->acceptor->close();
  const std::vector<HttpConnection*> open(state_->live.begin(), state_->live.end());
  for (HttpConnection* c : open) c->close();
}

HttpStats HttpServer::stats() const {
  HttpStats out = state_->stats;
  const net::AcceptStats& a = state_->acceptor->stats();
  out.accepted = a.accepted;
  out.not_allowed = a.not_allowed;
  out.refused = a.refused;
  return out;
}

std::size_t HttpServer::client_count() const {
  return state_->live.size();
}

}  // namespace drivegate::http
