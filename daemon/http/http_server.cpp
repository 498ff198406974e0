#include "http_server.h"

#include <spdlog/spdlog.h>

#include <vector>

#include "http_connection.h"
#include "net/accept_errors.h"
#include "net/listen_host.h"

namespace drivegate::http {

namespace asio = boost::asio;
using asio::ip::tcp;

namespace {

void accept(const std::shared_ptr<HttpState>& state);

void on_accept(const std::shared_ptr<HttpState>& state, const boost::system::error_code& ec,
               tcp::socket socket) {
  if (state->closed || ec == asio::error::operation_aborted) return;
  if (!ec) {
    boost::system::error_code peer_ec;
    const auto peer = socket.remote_endpoint(peer_ec);
    boost::system::error_code ignored;
    if (peer_ec || !net::allowed(state->options.allow, peer.address())) {
      ++state->stats.not_allowed;
      state->log->debug("http: {} not in the allow list: closed at accept",
                        peer_ec ? peer_ec.message() : peer.address().to_string());
      socket.close(ignored);
    } else if (state->live.size() - state->capturing >= state->options.max_clients) {
      ++state->stats.refused;
      socket.close(ignored);
    } else {
      std::make_shared<HttpConnection>(state, std::move(socket))->start();
    }
  } else {
    net::after_accept_error(ec, "http", *state->log, state->accept_error_log, state->retry_timer,
                               [state] {
                                 if (!state->closed) accept(state);
                               });
    return;
  }
  accept(state);
}

void accept(const std::shared_ptr<HttpState>& state) {
  state->acceptor.async_accept([state](const boost::system::error_code& ec, tcp::socket socket) {
    on_accept(state, ec, std::move(socket));
  });
}

}  // namespace

HttpServer::HttpServer(asio::io_context& io, Content& content, HttpOptions options,
                       std::shared_ptr<spdlog::logger> log)
    : state_(std::make_shared<HttpState>(io, content, std::move(options), std::move(log))) {}

HttpServer::~HttpServer() {
  close();
}

std::error_code HttpServer::listen() {
  const auto host = net::parse_listen_host(state_->options.host);
  if (!host) return std::make_error_code(std::errc::invalid_argument);
  // Every interface here is every IPv4 one (the status page is for the plant's network).
  const asio::ip::address address =
      host->any ? asio::ip::address(asio::ip::address_v4::any()) : host->address;
  boost::system::error_code ec;
  const tcp::endpoint endpoint(address, state_->options.port);
  auto& a = state_->acceptor;
  a.open(endpoint.protocol(), ec);
  if (!ec) a.set_option(tcp::acceptor::reuse_address(true), ec);
  if (!ec) a.bind(endpoint, ec);
  if (!ec) a.listen(asio::socket_base::max_listen_connections, ec);
  if (ec) {
    boost::system::error_code ignored;
    a.close(ignored);
    return ec;
  }
  state_->log->info("http: status page, /api/v1/status and /metrics on http://{}:{}/",
                    address.to_string(), port());
  accept(state_);
  return {};
}

std::uint16_t HttpServer::port() const {
  boost::system::error_code ec;
  return state_->acceptor.local_endpoint(ec).port();
}

void HttpServer::close() {
  if (state_->closed) return;
  state_->closed = true;
  boost::system::error_code ignored;
  state_->acceptor.close(ignored);
  state_->retry_timer.cancel();
  const std::vector<HttpConnection*> open(state_->live.begin(), state_->live.end());
  for (HttpConnection* c : open) c->close();
}

const HttpStats& HttpServer::stats() const {
  return state_->stats;
}

std::size_t HttpServer::client_count() const {
  return state_->live.size();
}

}  // namespace drivegate::http
