// End-to-end test support: a Modbus TCP client that keeps several requests in flight on one
// connection, as a careless PLC program or a SCADA script in a loop does. It writes its own MBAP
// frames (no client library would pipeline), reads the answers in whatever order they come, and
// records each request's exception code and how long its answer took.
//
//   drivegate::test::Flood flood(port, unit, /*in_flight=*/2);
//   flood.run(6s, [](std::uint64_t i) { return fc06(1, i % 2 ? 1000 : 1200); });
//   EXPECT_EQ(flood.count(0x0B), 0u);
#pragma once

#include <netinet/tcp.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <vector>

#include "e2e.h"

namespace drivegate::test {

// The PDU of FC 06 (write single register).
inline std::vector<std::uint8_t> fc06(std::uint16_t address, std::uint16_t value) {
  return {0x06, static_cast<std::uint8_t>(address >> 8), static_cast<std::uint8_t>(address),
          static_cast<std::uint8_t>(value >> 8), static_cast<std::uint8_t>(value)};
}

class Flood {
 public:
  using Clock = std::chrono::steady_clock;
  struct Answer {
    int code;  // 0: a normal response; else the exception code; -1: none came
    std::chrono::microseconds took;
  };

  Flood(int port, std::uint8_t unit, std::size_t in_flight)
      : fd_(connect_loopback(port)),
        connected_(fd_ >= 0),
        unit_(unit),
        in_flight_(std::max<std::size_t>(1, in_flight)) {
    int one = 1;
    if (connected_) ::setsockopt(fd_, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  }
  ~Flood() {
    if (fd_ >= 0) ::close(fd_);
  }
  Flood(const Flood&) = delete;
  Flood& operator=(const Flood&) = delete;

  [[nodiscard]] bool connected() const { return connected_; }

  // For `span`, keeps `in_flight` requests outstanding: request i is pdu(i). Then waits up to
  // `drain` for the last answers; requests never answered are recorded with code -1.
  void run(std::chrono::milliseconds span,
           const std::function<std::vector<std::uint8_t>(std::uint64_t)>& pdu,
           std::chrono::milliseconds drain = std::chrono::seconds(10)) {
    const auto stop = Clock::now() + span;
    while (connected_) {
      const bool sending = Clock::now() < stop;
      while (sending && sent_.size() < in_flight_) send(pdu(next_));
      if (sent_.empty()) break;
      if (!sending && Clock::now() >= stop + drain) break;
      receive(std::chrono::milliseconds(50));
    }
    for (const auto& [tid, at] : sent_) {
      answers_.push_back({-1, std::chrono::duration_cast<std::chrono::microseconds>(
                                  Clock::now() - at)});
    }
    sent_.clear();
  }

  [[nodiscard]] const std::vector<Answer>& answers() const { return answers_; }
  [[nodiscard]] std::size_t count(int code) const {
    return static_cast<std::size_t>(std::count_if(answers_.begin(), answers_.end(),
                                                  [code](const Answer& a) { return a.code == code; }));
  }
  [[nodiscard]] std::chrono::microseconds slowest() const {
    std::chrono::microseconds m{0};
    for (const auto& a : answers_) m = std::max(m, a.took);
    return m;
  }

 private:
  void send(const std::vector<std::uint8_t>& pdu) {
    const auto tid = static_cast<std::uint16_t>(next_++);
    const auto adu = mbap_adu(tid, unit_, pdu);
    if (::send(fd_, adu.data(), adu.size(), MSG_NOSIGNAL) != static_cast<ssize_t>(adu.size())) {
      connected_ = false;
      return;
    }
    sent_[tid] = Clock::now();
  }
  void receive(std::chrono::milliseconds wait) {
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(wait.count())) <= 0) return;
    std::uint8_t buf[4096];
    const ssize_t n = ::recv(fd_, buf, sizeof buf, 0);
    if (n <= 0) {
      connected_ = false;
      return;
    }
    in_.insert(in_.end(), buf, buf + n);
    while (in_.size() >= 8) {
      const std::size_t size = 6u + ((std::size_t{in_[4]} << 8) | in_[5]);
      if (in_.size() < size) break;
      const auto tid = static_cast<std::uint16_t>((in_[0] << 8) | in_[1]);
      const std::uint8_t fc = in_[7];
      const int code = (fc & 0x80) != 0 && size > 8 ? in_[8] : 0;
      if (const auto it = sent_.find(tid); it != sent_.end()) {
        answers_.push_back(
            {code, std::chrono::duration_cast<std::chrono::microseconds>(Clock::now() - it->second)});
        sent_.erase(it);
      }
      in_.erase(in_.begin(), in_.begin() + static_cast<long>(size));
    }
  }

  int fd_ = -1;
  bool connected_ = false;
  std::uint8_t unit_;
  std::size_t in_flight_;
  std::uint64_t next_ = 0;
  std::map<std::uint16_t, Clock::time_point> sent_;
  std::vector<std::uint8_t> in_;
  std::vector<Answer> answers_;
};

}  // namespace drivegate::test
