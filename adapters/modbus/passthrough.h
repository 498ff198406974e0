// The pass-through driver (passthrough = true): the device's unit id is a transparent window
// onto a Modbus slave. Every request the gateway lets through for it (whole and well-formed:
// daemon/gateway/forward_access.h) reaches this driver as a forward part (Driver::forwards),
// goes on the line as it is, address and CRC or LRC around it, and the
// slave's reply PDU, exception replies included, goes back to the client as it came. Nothing is
// polled but a presence probe, so the device's common block says only whether the slave answers.
//
// Choices (docs/profiles.md, "Pass-through"):
//   - A forwarded request is sent once: the client's own retries decide, and a write is never
//     put on the line twice for one request.
//   - The probe is a read of one holding register at 0 (FC 03) every poll interval: any reply
//     from the slave's address, an exception included, proves it is there. It carries no data,
//     so the device's data age never starts: the gateway holds nothing of a pass-through slave.
//   - A forwarded request not on the line within its send limit fails (no_response) and is never
//     sent, like any write, so nothing the client was told failed reaches the slave later.
#pragma once

#include <optional>
#include <vector>

#include "codec.h"
#include "drivegate/driver_base.h"
#include "drivegate/write_ledger.h"
#include "settings.h"

namespace drivegate::modbus_device {

class PassthroughDriver final : public DriverBase {
 public:
  // `address`: 1..247 (Serial Line 2.2). `char_time`: one character as the bus runs it.
  PassthroughDriver(std::uint8_t address, PassthroughSettings settings,
                    std::chrono::nanoseconds char_time, Millis poll_interval);

  // check() and apply() take only forward parts: the device has no command, setpoint or points
  // of its own.
  DRIVEGATE_DRIVER_OVERRIDES;
  [[nodiscard]] bool forwards() const override { return true; }

 private:
  // A forwarded request; its ticket and send-by are the ledger's.
  struct Forward {
    Bytes pdu;
  };
  using Forwards = WriteLedger<Forward>;
  struct InFlight {
    std::uint8_t function = 0;
    std::optional<Forwards::Entry> forward;  // nothing: the presence probe
  };

  [[nodiscard]] Millis send_limit() const;
  void abandon();

  std::uint8_t address_;
  PassthroughSettings settings_;
  std::chrono::nanoseconds char_time_;
  Millis poll_interval_;

  Forwards queued_{completions_};
  std::optional<InFlight> inflight_;
  TimePoint probe_due_{};
  TimePoint last_now_{};
};

}  // namespace drivegate::modbus_device
