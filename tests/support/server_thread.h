// A network server of the daemon (modbus::Server, http::HttpServer) listening on loopback, run by
// its own io_context thread while the test drives real sockets against it, on a clock the test
// moves (manual_clock.h): its timeouts are tested without waiting for them. `Source` is what the
// server serves from (the Modbus fake backend, the HTTP fake content), built before the server
// and gone after it. The server's thread looks at what a test waits for after every handler it
// runs, so a test waits for the event itself, never a guessed time.
#pragma once

#include <spdlog/sinks/null_sink.h>
#include <spdlog/spdlog.h>

#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
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
    thread_ = std::thread([this] {
      while (io_.run_one() > 0) look();
    });
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
  // Waits (up to 5 s of real time) until `done()` holds: the server's thread runs it now and
  // again after each handler it runs (a client's bytes read, a timer, a connection closed), the
  // only moments at which what it looks at can change.
  template <class Done>
  bool eventually(Done done) {
    std::unique_lock lock(wait_mutex_);
    wait_for_ = [&done] { return static_cast<bool>(done()); };
    waited_ = false;
    boost::asio::post(io_, [] {});  // a first look at once
    const bool met = wait_cv_.wait_for(lock, std::chrono::seconds(5), [this] { return waited_; });
    wait_for_ = nullptr;
    return met;
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
  // What eventually() waits for, looked at on the server's thread after each handler.
  std::mutex wait_mutex_;
  std::condition_variable wait_cv_;
  std::function<bool()> wait_for_;
  bool waited_ = false;
  std::thread thread_;

  void look() {
    const std::lock_guard lock(wait_mutex_);
    if (wait_for_ && !waited_ && wait_for_()) {
      waited_ = true;
      wait_cv_.notify_all();
    }
  }
};

}  // namespace drivegate::test
