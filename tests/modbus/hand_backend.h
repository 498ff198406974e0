// A backend by hand for the slave listeners' tests (modbus/backend.h): units 1 and 2 exist,
// holding registers read as 100 + address, and every write waits until the test calls the
// `done` it left in `pending`.
#pragma once

#include <chrono>
#include <memory>
#include <optional>
#include <vector>

#include "modbus/backend.h"

namespace drivegate::slave {

class HandBackend final : public modbus::Backend {
 public:
  using Exception = modbus::Exception;

  Exception read(const Session& session, std::uint8_t unit, Table, std::uint16_t address,
                 std::span<std::uint16_t> out) override {
    fault_reads.push_back(session.fault_reads);
    if (!serves(unit)) return Exception::gateway_path_unavailable;
    if (address == kFaultState && session.fault_reads) {
      session.fault_reads->served(this, true, std::chrono::steady_clock::now());
    }
    for (std::size_t i = 0; i < out.size(); ++i)
      out[i] = static_cast<std::uint16_t>(100 + address + i);
    return Exception::none;
  }
  Exception write(const Session& session, std::uint8_t unit, Table, std::uint16_t address,
                  std::span<const std::uint16_t> values, modbus::WriteDone done) override {
    fault_reads.push_back(session.fault_reads);
    writes_fault_seen.push_back(session.fault_reads ? session.fault_reads->fault_seen(this)
                                                    : std::nullopt);
    if (!serves(unit)) return Exception::gateway_path_unavailable;
    writes.push_back({unit, address, std::vector<std::uint16_t>(values.begin(), values.end())});
    pending.push_back(std::move(done));
    return Exception::none;
  }
  void refused_write(const Session&, std::uint8_t unit, std::span<const std::uint8_t>) override {
    refused.push_back(unit);
  }
  void refused_broadcast(const Session&, std::span<const std::uint8_t>) override {
    ++refused_broadcasts;
  }
  bool serves(std::uint8_t unit) const override { return unit == 1 || unit == 2; }

  // The session's record of the faults its client read (gateway/fault_reads.h), each read and
  // write in turn. Register kFaultState reads as the gateway's fault state does, showing a
  // fault; what each write found there, in order.
  std::vector<std::shared_ptr<FaultReads>> fault_reads;
  static constexpr std::uint16_t kFaultState = 0;
  std::vector<std::optional<FaultReads::TimePoint>> writes_fault_seen;

  struct Write {
    std::uint8_t unit;
    std::uint16_t address;
    std::vector<std::uint16_t> values;
  };
  std::vector<Write> writes;
  std::vector<modbus::WriteDone> pending;
  std::vector<std::uint8_t> refused;
  int refused_broadcasts = 0;
};

}  // namespace drivegate::slave
