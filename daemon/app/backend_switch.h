// The Modbus server's backend across reloads: it forwards to the current gateway, so a SIGHUP
// swaps the devices without closing a single Modbus TCP connection.
#pragma once

#include "modbus/backend.h"

namespace drivegate {

class BackendSwitch : public modbus::Backend {
 public:
  void set(modbus::Backend* target) { target_ = target; }
  modbus::Exception read(const Session& session, std::uint8_t unit, Table table,
                         std::uint16_t address, std::span<std::uint16_t> out) override {
    if (target_ == nullptr) return modbus::Exception::gateway_path_unavailable;
    return target_->read(session, unit, table, address, out);
  }
  modbus::Exception write(const Session& session, std::uint8_t unit, Table table,
                          std::uint16_t address, std::span<const std::uint16_t> values,
                          modbus::WriteDone done) override {
    if (target_ == nullptr) return modbus::Exception::gateway_path_unavailable;
    return target_->write(session, unit, table, address, values, std::move(done));
  }

 private:
  modbus::Backend* target_ = nullptr;
};

}  // namespace drivegate
