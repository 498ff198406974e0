// End-to-end test support: a TCP proxy on loopback between a client under test (drivegated's MQTT
// client) and a real server (mosquitto), that can fail the way networks fail without anyone
// closing anything:
//
//   drivegate::test::FaultProxy proxy(broker.port());  // listens on 127.0.0.1:proxy.port()
//   proxy.hold();      // half-open: the connections open now stop forwarding, both ways, and stay
//                      // open (a cable pulled, a NAT or firewall that lost its state); connections
//                      // made after it are forwarded (the route is back for new ones)
//   proxy.release();   // a stall: the held connections forward again, what waited included
//   proxy.hold_new(true);     // connections made from now on are held too (a server that accepts
//                             // and never answers)
//   proxy.cut_after(30'000);  // each connection, from its start, forwards this many bytes from the
//                             // client and is then reset (both sides), the rest of the bytes lost
//   proxy.cut_after(0);       // no more cutting
//
// One thread, poll(2), non-blocking sockets; every socket is closed when the proxy is destroyed.
// The counters say what went through (client_bytes(), connections()).
#pragma once

#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "loopback.h"

namespace drivegate::test {

class FaultProxy {
 public:
  explicit FaultProxy(int upstream_port) : upstream_port_(upstream_port) {
    listener_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
    const int one = 1;
    ::setsockopt(listener_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    sockaddr_in a = loopback(0);
    socklen_t size = sizeof a;
    if (::bind(listener_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 ||
        ::listen(listener_, 16) != 0 ||
        ::getsockname(listener_, reinterpret_cast<sockaddr*>(&a), &size) != 0) {
      ::close(listener_);
      throw std::runtime_error("FaultProxy: cannot listen on 127.0.0.1");
    }
    port_ = ntohs(a.sin_port);
    if (::pipe2(wake_, O_CLOEXEC | O_NONBLOCK) != 0) {
      ::close(listener_);
      throw std::runtime_error("FaultProxy: pipe");
    }
    thread_ = std::thread([this] { run(); });
  }
  ~FaultProxy() {
    stop_ = true;
    poke();
    thread_.join();
    for (auto& l : links_) l->close_both(false);
    ::close(listener_);
    ::close(wake_[0]);
    ::close(wake_[1]);
  }
  FaultProxy(const FaultProxy&) = delete;
  FaultProxy& operator=(const FaultProxy&) = delete;

  [[nodiscard]] int port() const { return port_; }
  [[nodiscard]] std::string url() const { return "mqtt://127.0.0.1:" + std::to_string(port_); }

  void hold() {
    command([](FaultProxy& p) {
      for (auto& l : p.links_) l->held = true;
    });
  }
  void release() {
    command([](FaultProxy& p) {
      for (auto& l : p.links_) l->held = false;
    });
  }
  void hold_new(bool on) {
    command([on](FaultProxy& p) { p.hold_new_ = on; });
  }
  void cut_after(std::uint64_t bytes) {
    command([bytes](FaultProxy& p) { p.cut_after_ = bytes; });
  }
  // Connections accepted so far, and bytes forwarded from clients to the server (all of them).
  [[nodiscard]] std::uint64_t connections() const { return connections_; }
  [[nodiscard]] std::uint64_t client_bytes() const { return client_bytes_; }
  [[nodiscard]] std::uint64_t cuts() const { return cuts_; }

 private:
  struct Link {
    int client = -1;
    int server = -1;
    bool held = false;
    std::uint64_t from_client = 0;
    std::string to_server;  // read from the client, not yet written
    std::string to_client;
    void close_both(bool reset) {
      for (int* fd : {&client, &server}) {
        if (*fd < 0) continue;
        if (reset) {
          const linger l{1, 0};  // RST: the peer sees the connection reset, not a clean end
          ::setsockopt(*fd, SOL_SOCKET, SO_LINGER, &l, sizeof l);
        }
        ::close(*fd);
        *fd = -1;
      }
    }
    [[nodiscard]] bool open() const { return client >= 0 && server >= 0; }
  };

  template <class F>
  void command(F f) {
    {
      const std::lock_guard lock(mutex_);
      pending_.emplace_back(std::move(f));
    }
    poke();
    // Applied before this returns: the test's next step sees it in force.
    std::unique_lock lock(mutex_);
    applied_.wait(lock, [this] { return pending_.empty(); });
  }
  void poke() {
    const char c = 0;
    [[maybe_unused]] const auto n = ::write(wake_[1], &c, 1);
  }

  void accept_one() {
    const int c = ::accept4(listener_, nullptr, nullptr, SOCK_CLOEXEC | SOCK_NONBLOCK);
    if (c < 0) return;
    const int s = connect_loopback(upstream_port_);
    if (s < 0) {
      ::close(c);
      return;
    }
    ::fcntl(s, F_SETFL, ::fcntl(s, F_GETFL) | O_NONBLOCK);
    const int one = 1;
    ::setsockopt(c, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    ::setsockopt(s, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    auto l = std::make_unique<Link>();
    l->client = c;
    l->server = s;
    l->held = hold_new_;
    links_.push_back(std::move(l));
    ++connections_;
  }

  // Moves what `from` has into `buffer`: false on EOF or error.
  static bool pull(int from, std::string& buffer, std::uint64_t& counted) {
    char chunk[16384];
    const ssize_t n = ::read(from, chunk, sizeof chunk);
    if (n == 0) return false;
    if (n < 0) return errno == EAGAIN || errno == EINTR;
    buffer.append(chunk, static_cast<std::size_t>(n));
    counted += static_cast<std::uint64_t>(n);
    return true;
  }
  static bool push(int to, std::string& buffer) {
    if (buffer.empty()) return true;
    const ssize_t n = ::send(to, buffer.data(), buffer.size(), MSG_NOSIGNAL);
    if (n < 0) return errno == EAGAIN || errno == EINTR;
    buffer.erase(0, static_cast<std::size_t>(n));
    return true;
  }

  void run() {
    while (!stop_) {
      std::vector<pollfd> fds = {{wake_[0], POLLIN, 0}, {listener_, POLLIN, 0}};
      for (const auto& l : links_) {
        if (l->held || !l->open()) continue;
        fds.push_back(
            {l->client, static_cast<short>(POLLIN | (l->to_client.empty() ? 0 : POLLOUT)), 0});
        fds.push_back(
            {l->server, static_cast<short>(POLLIN | (l->to_server.empty() ? 0 : POLLOUT)), 0});
      }
      ::poll(fds.data(), fds.size(), 100);
      if (fds[0].revents & POLLIN) {
        char drain[64];
        while (::read(wake_[0], drain, sizeof drain) > 0) {
        }
      }
      {
        const std::lock_guard lock(mutex_);
        for (auto& f : pending_) f(*this);
        pending_.clear();
        applied_.notify_all();
      }
      if (fds[1].revents & POLLIN) accept_one();
      for (auto& l : links_) {
        if (l->held || !l->open()) continue;
        std::uint64_t ignored = 0;
        const std::uint64_t before = l->from_client;
        bool ok =
            pull(l->client, l->to_server, l->from_client) && pull(l->server, l->to_client, ignored);
        client_bytes_ += l->from_client - before;
        if (ok && cut_after_ != 0 && l->from_client >= cut_after_) {
          // Up to the limit goes through; the rest is lost with the connection.
          const std::uint64_t over = l->from_client - cut_after_;
          if (over < l->to_server.size()) {
            l->to_server.resize(l->to_server.size() - over);
          } else {
            l->to_server.clear();
          }
          push(l->server, l->to_server);
          l->close_both(true);
          ++cuts_;
          continue;
        }
        ok = ok && push(l->server, l->to_server) && push(l->client, l->to_client);
        if (!ok) {
          push(l->client, l->to_client);  // what the server said last still reaches the client
          l->close_both(false);
        }
      }
      std::erase_if(links_, [](const auto& l) { return !l->open(); });
    }
  }

  int upstream_port_;
  int listener_ = -1;
  int port_ = 0;
  int wake_[2] = {-1, -1};
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::mutex mutex_;
  std::vector<std::function<void(FaultProxy&)>> pending_;
  std::condition_variable applied_;           // pending_ emptied
  std::vector<std::unique_ptr<Link>> links_;  // the proxy thread's
  std::uint64_t cut_after_ = 0;               // the proxy thread's
  bool hold_new_ = false;                     // the proxy thread's
  std::atomic<std::uint64_t> connections_{0};
  std::atomic<std::uint64_t> client_bytes_{0};
  std::atomic<std::uint64_t> cuts_{0};
};

}  // namespace drivegate::test
