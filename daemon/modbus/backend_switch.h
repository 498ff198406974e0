// The Modbus server's backend: the current gateway, whose outcomes it answers as Modbus exceptions
// (modbus_exception.h). It forwards to whichever gateway is current across reloads, so a SIGHUP
// swaps the devices without closing a single Modbus TCP connection.
#pragma once

#include "gateway/gateway.h"
#include "modbus/backend.h"
#include "modbus/modbus_exception.h"

namespace drivegate {

class BackendSwitch : public modbus::Backend {
 public:
  void set(Gateway* target) { target_ = target; }
  modbus::Exception read(const Session& session, std::uint8_t unit, Table table,
                         std::uint16_t address, std::span<std::uint16_t> out) override {
    // No gateway yet: no device at any unit id.
    if (target_ == nullptr) return modbus_exception(Outcome::no_such_device);
    return modbus_exception(target_->read(session, unit, table, address, out));
  }
  modbus::Exception write(const Session& session, std::uint8_t unit, Table table,
                          std::uint16_t address, std::span<const std::uint16_t> values,
                          modbus::WriteDone done) override {
    if (target_ == nullptr) return modbus_exception(Outcome::no_such_device);
    return modbus_exception(
        target_->write(session, unit, table, address, values,
                       [done = std::move(done)](Outcome o) { done(modbus_exception(o)); }));
  }
  void refused_write(const Session& session, std::uint8_t unit,
                     std::span<const std::uint8_t> request) override {
    if (target_ != nullptr) target_->refused_write(session, unit, request);
  }
  void refused_broadcast(const Session& session, std::span<const std::uint8_t> request) override {
    if (target_ != nullptr) target_->refused_broadcast(session, request);
  }
  bool serves(std::uint8_t unit) const override {
    return target_ != nullptr && target_->serves(unit);
  }
  bool forwards(std::uint8_t unit) const override {
    return target_ != nullptr && target_->forwards(unit);
  }
  modbus::Exception forward(const Session& session, std::uint8_t unit,
                            std::span<const std::uint8_t> request,
                            modbus::ForwardDone done) override {
    if (target_ == nullptr) return modbus_exception(Outcome::no_such_device);
    return modbus_exception(
        target_->forward(session, unit, request,
                         [done = std::move(done)](Outcome o, std::span<const std::uint8_t> reply) {
                           done(modbus_exception(o), reply);
                         }));
  }

 private:
  Gateway* target_ = nullptr;
};

}  // namespace drivegate
