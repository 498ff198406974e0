// A register image for the Modbus server tests: four tables of 4096 entries with a hole at
// 0x0400..0x04FF (unmapped: 0x02), units 1 and 2 known (others: 0x0A), input tables read-only.
// Writes complete at once (inside write()), later (complete()), or are refused by the device.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <deque>
#include <optional>
#include <vector>

#include "backend.h"

namespace drivegate::modbus::test {

class FakeBackend : public Backend {
 public:
  enum class Mode { immediate, deferred };
  static constexpr std::size_t kSize = 4096;
  static constexpr std::uint16_t kHoleBegin = 0x0400;
  static constexpr std::uint16_t kHoleEnd = 0x0500;

  struct Write {
    std::uint8_t unit;
    Table table;
    std::uint16_t address;
    std::vector<std::uint16_t> values;
  };

  FakeBackend() {
    for (auto& t : tables_) t.assign(kSize, 0);
  }

  std::vector<std::uint16_t>& table(Table t) { return tables_[static_cast<int>(t)]; }

  Exception read(const Session& session, std::uint8_t unit, Table t, std::uint16_t address,
                 std::span<std::uint16_t> out) override {
    ++reads;
    last_session = session;
    if (auto e = check(unit, address, out.size()); e != Exception::none) return e;
    if (t == Table::input && address == kFaultState && session.fault_reads) {
      session.fault_reads->served(this, true, std::chrono::steady_clock::now());
    }
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = table(t)[address + i];
    return Exception::none;
  }

  Exception write(const Session& session, std::uint8_t unit, Table t, std::uint16_t address,
                  std::span<const std::uint16_t> values, WriteDone done) override {
    last_session = session;
    writes_fault_seen.push_back(session.fault_reads ? session.fault_reads->fault_seen(this)
                                                    : std::nullopt);
    if (auto e = check(unit, address, values.size()); e != Exception::none) return e;
    // As the gateway does for points beyond the common block: backend.h's only 0x01.
    if (maintain_from && address + values.size() > *maintain_from &&
        session.access < AccessLevel::maintain) {
      return Exception::illegal_function;
    }
    if (t == Table::input || t == Table::discrete) {
      return Exception::illegal_data_address;
    }
    if (reject_value && !values.empty() && values[0] == *reject_value) {
      return Exception::illegal_data_value;
    }
    writes.push_back({unit, t, address, {values.begin(), values.end()}});
    if (mode == Mode::immediate) {
      apply(writes.back());
      done(device_result);
    } else {
      pending.push_back({std::move(done), writes.size() - 1});
    }
    return Exception::none;
  }

  // Unit 5 is a pass-through one: every request for it is kept until complete_forward().
  static constexpr std::uint8_t kForwardingUnit = 5;
  [[nodiscard]] bool forwards(std::uint8_t unit) const override { return unit == kForwardingUnit; }
  Exception forward(const Session& session, std::uint8_t, std::span<const std::uint8_t> request,
                    ForwardDone done) override {
    last_session = session;
    // As the gateway does (gateway/forward_access.h): a read session forwards 03 only here.
    if (session.access == AccessLevel::read && request[0] != 0x03) {
      return Exception::illegal_function;
    }
    forwarded.emplace_back(request.begin(), request.end());
    forwards_pending.push_back(std::move(done));
    return Exception::none;
  }
  // Answers the oldest forwarded request with `reply` (or `result`, when not none).
  void complete_forward(std::vector<std::uint8_t> reply, Exception result = Exception::none) {
    auto done = std::move(forwards_pending.front());
    forwards_pending.pop_front();
    done(result, reply);
  }
  std::vector<std::vector<std::uint8_t>> forwarded;
  std::deque<ForwardDone> forwards_pending;

  // Completes the oldest deferred write: applies it when `result` is none.
  void complete(Exception result = Exception::none) {
    auto p = std::move(pending.front());
    pending.pop_front();
    if (result == Exception::none) apply(writes[p.index]);
    p.done(result);
  }

  Mode mode = Mode::immediate;
  Exception device_result = Exception::none;  // immediate mode: what `done` reports
  std::optional<std::uint16_t> reject_value;  // synchronous 0x03 for this first value
  std::vector<Write> writes;
  struct Pending {
    WriteDone done;
    std::size_t index;
  };
  std::deque<Pending> pending;
  std::size_t reads = 0;
  // Writes reaching this address or above need AccessLevel::maintain (else 0x01, as the gateway
  // answers for points beyond the common command block).
  std::optional<std::uint16_t> maintain_from;
  Session last_session;  // of the last read or write
  // Input register kFaultState reads as the gateway's fault state does: the session's FaultReads
  // is told it showed a fault (gateway/fault_reads.h). What each write found there, in order.
  static constexpr std::uint16_t kFaultState = 0;
  std::vector<std::optional<FaultReads::TimePoint>> writes_fault_seen;

 private:
  Exception check(std::uint8_t unit, std::uint16_t address, std::size_t count) const {
    if (unit != 1 && unit != 2) return Exception::gateway_path_unavailable;
    const std::size_t end = std::size_t{address} + count;
    if (end > kSize || (address < kHoleEnd && end > kHoleBegin)) {
      return Exception::illegal_data_address;
    }
    return Exception::none;
  }
  void apply(const Write& w) {
    if (device_result != Exception::none && mode == Mode::immediate) return;
    for (std::size_t i = 0; i < w.values.size(); ++i) table(w.table)[w.address + i] = w.values[i];
  }

  std::array<std::vector<std::uint16_t>, 4> tables_;
};

}  // namespace drivegate::modbus::test
