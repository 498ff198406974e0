// One Modbus TCP connection's request path without the socket: bytes arrive in segments, every
// complete MBAP frame is parsed and dispatched in order exactly as daemon/modbus/connection.cpp
// does (a malformed header closes the connection, a write past the pending cap waits, a pending
// write's reply is built by Dispatcher::complete once its `done` fired; every request for a
// pass-through unit goes to Dispatcher::forward and is answered with its reply), and every reply is
// checked against the Application Protocol's shape rules.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "backend.h"
#include "mbap.h"
#include "pdu.h"

namespace drivegate::fuzz {

class ModbusStream {
 public:
  // `settle` is called when the pending-write cap blocks the next request: it should make the
  // backend complete at least one write; false when it cannot (the rest of the input waits).
  ModbusStream(modbus::Backend& backend, std::function<bool()> settle);

  // One TCP segment. Returns false once the connection is closed (malformed header).
  bool receive(std::span<const std::uint8_t> segment);
  // Builds the replies of writes whose `done` has fired (the connection's posted completion).
  void complete_writes();

  [[nodiscard]] std::size_t replies() const { return replies_; }
  [[nodiscard]] std::size_t pending() const { return outstanding_; }

 private:
  struct Slot {
    bool used = false;
    bool done = false;
    std::uint32_t generation = 0;
    modbus::Exception result = modbus::Exception::none;
    std::uint16_t transaction = 0;
    std::uint8_t unit = 0;
    std::vector<std::uint8_t> request;
    bool forwarded = false;               // to a pass-through unit (Dispatcher::forward)
    std::vector<std::uint8_t> reply;      // its device's reply PDU
  };
  void dispatch(const modbus::MbapHeader& header, std::span<const std::uint8_t> pdu);
  void check_reply(std::span<const std::uint8_t> request, std::span<const std::uint8_t> reply);

  std::function<bool()> settle_;
  modbus::Dispatcher dispatcher_;
  // Every right: the backend's checks are what is fuzzed.
  const Session session_{AccessLevel::maintain, WordOrder::big};
  std::vector<std::uint8_t> rx_;
  // Shared with the `done` closures, which may outlive the stream (the backend owns them).
  std::shared_ptr<std::vector<Slot>> slots_;
  std::size_t outstanding_ = 0;
  std::size_t replies_ = 0;
  bool closed_ = false;
  std::array<std::uint8_t, modbus::kMaxPduSize> out_{};
};

}  // namespace drivegate::fuzz
