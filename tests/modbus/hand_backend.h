// A backend by hand for the slave listeners' tests (modbus/backend.h): units 1 and 2 exist,
// holding registers read as 100 + address, and every write waits until the test calls the
// `done` it left in `pending`.
#pragma once

#include <vector>

#include "modbus/backend.h"

namespace drivegate::slave {

class HandBackend final : public modbus::Backend {
 public:
  using Exception = modbus::Exception;

  Exception read(const Session&, std::uint8_t unit, Table, std::uint16_t address,
                 std::span<std::uint16_t> out) override {
    if (!serves(unit)) return Exception::gateway_path_unavailable;
    for (std::size_t i = 0; i < out.size(); ++i)
      out[i] = static_cast<std::uint16_t>(100 + address + i);
    return Exception::none;
  }
  Exception write(const Session&, std::uint8_t unit, Table, std::uint16_t address,
                  std::span<const std::uint16_t> values, modbus::WriteDone done) override {
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
