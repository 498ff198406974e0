// The test-drive driver: polls the drive's state with `read`; a command goes out as run, stop or
// reset and is in force once the drive's reply to it came; a setpoint is stored while the drive
// is stopped and sent as a run while it turns. Exists for the core's tests (codec.h).
#pragma once

#include <cstdint>
#include <optional>

#include "codec.h"
#include "drivegate/driver_base.h"
#include "drivegate/write_ledger.h"

namespace drivegate::testdrive {

class TestDriveDriver final : public DriverBase {
 public:
  TestDriveDriver(std::uint8_t address, Millis poll_interval);

  DRIVEGATE_DRIVER_OVERRIDES;

 private:
  // A write on its way: the frame that carries it out, and the command it puts in force.
  struct Write {
    Request request;
    Command command = Command::stop;
  };
  using Writes = WriteLedger<Write>;

  [[nodiscard]] Exchange exchange(const Request& r) const;
  [[nodiscard]] std::optional<Request> run_request(Command c, std::int32_t rpm) const;
  void apply_reply(const Reply& r);

  std::uint8_t address_;
  Millis poll_interval_;
  Writes writes_{completions_};
  std::optional<Op> in_flight_;  // the op of the request on the line
  bool write_on_line_ = false;   // that request is writes_.front()'s
  TimePoint last_sent_{};
  std::optional<TimePoint> next_poll_;  // none: at once
};

}  // namespace drivegate::testdrive
