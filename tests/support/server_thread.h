// A network server of the daemon (modbus::Server, http::HttpServer) listening on loopback, run by
// its own io_context thread while the test drives real sockets against it, on a clock the test
// moves (manual_clock.h): its timeouts are tested without waiting for them. `Source` is what the
// server serves from (the Modbus fake backend, the HTTP fake content), built before the server
// and gone after it.
#pragma once

#include <spdlog/sinks/null_sink.h>
#include <spdlog/spdlog.h>

#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>
#include <chrono>
#include <future>
#include <memory>
#include <string>
#include <system_error>
#include <thread>
#include <utility>

#include "manual_clock.h"

namespace drivegate::test {

template <class Server, class Source>
class ServerThread {
 public:
  template <class Options>
  ServerThread(Options options, const std::string& name) {
    auto log =
        std::make_shared<spdlog::logger>(name, std::make_shared<spdlog::sinks::null_sink_st>());
    server_ = std::make_unique<Server>(io_, clock_, source_, std::move(options), log);
    error_ = server_->listen();
    thread_ = std::thread([this] { io_.run(); });
  }
  ~ServerThread() {
    on_io([this] { server_->close(); });
    guard_.reset();
    thread_.join();
  }
  ServerThread(const ServerThread&) = delete;
  ServerThread& operator=(const ServerThread&) = delete;

  [[nodiscard]] std::error_code listen_error() const { return error_; }

  // Runs `f` on the server's thread and returns its result.
  template <class F>
  auto on_io(F f) -> decltype(f()) {
    std::packaged_task<decltype(f())()> task(std::move(f));
    auto result = task.get_future();
    boost::asio::post(io_, [&task] { task(); });
    return result.get();
  }
  Server& server() { return *server_; }
  auto stats() {
    return on_io([this] { return server_->stats(); });
  }
  std::size_t clients() {
    return on_io([this] { return server_->client_count(); });
  }
  // Waits (up to 5 s of real time) until `done()`, run on the server's thread, holds.
  template <class Done>
  bool eventually(Done done) {
    for (int i = 0; i < 500; ++i) {
      if (on_io(done)) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return false;
  }
  bool wait_clients(std::size_t n) {
    return eventually([this, n] { return server_->client_count() == n; });
  }
  // Moves the server's clock on: whatever falls due in `d` happens (in its event loop's next
  // turns; wait for its effect on the sockets).
  void advance(std::chrono::steady_clock::duration d) {
    on_io([this, d] { clock_.advance(d); });
  }
  // The server's own view of now, for the few tests that measure against it.
  net::TimePoint now() {
    return on_io([this] { return clock_.now(); });
  }

 protected:
  Source& source() { return source_; }

 private:
  // Before io_: handlers the io_context still holds when it is destroyed may own timers, which
  // detach from their clock as they go (daemon/app/daemon.h says the same).
  ManualClock clock_;
  boost::asio::io_context io_;
  boost::asio::executor_work_guard<boost::asio::io_context::executor_type> guard_{
      io_.get_executor()};
  Source source_;
  std::unique_ptr<Server> server_;
  std::error_code error_;
  std::thread thread_;
};

}  // namespace drivegate::test
