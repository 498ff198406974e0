// The test-drive driver: polls the drive's state with `read`; a command goes out as run, stop or
// reset, and accel_time as accel, each in force once the drive's reply to it came; a refusal, or
// a turn of attempts unanswered, is resent until the write's deadline; a setpoint is stored while
// the drive is stopped and sent as a run while it turns. Exists for the core's tests (codec.h).
#pragma once

#include <array>
#include <cstdint>
#include <optional>

#include "codec.h"
#include "drivegate/driver_base.h"
#include "drivegate/options.h"
#include "drivegate/write_ledger.h"

namespace drivegate::testdrive {

// The point indices of make_points().
namespace pt {
inline constexpr std::size_t drive_state = 0;
inline constexpr std::size_t accel_time = 1;
}  // namespace pt

// The device options: the schema the descriptor publishes, and the values the driver uses.
inline constexpr std::array<OptionSpec, 2> kOptionSchema = {{
    {"one_way", OptionType::boolean, "false",
     "the drive turns forward only: a run_reverse is refused as a value it cannot take"},
    {"accel_time_ms", OptionType::integer, "0",
     "the accel time the drive is set to each time it is reached (op accel, 100 ms units); 0 "
     "leaves it at its own",
     0, 6553500},
}};
struct Settings {
  bool one_way = false;                      // the drive turns forward only: run_reverse is refused
  std::optional<std::uint16_t> accel_100ms;  // set each time the drive is reached
};
// The settings `options` (kOptionSchema's) say.
Settings parse_settings(const Options& options);

class TestDriveDriver final : public DriverBase {
 public:
  TestDriveDriver(std::uint8_t address, Millis poll_interval, Settings settings = {});

  DRIVEGATE_DRIVER_OVERRIDES;

 private:
  // A write on its way: the frame that carries it out, and the command it puts in force.
  struct Write {
    Request request;
    Command command = Command::stop;  // in force once answered (not for accel)
  };
  using Writes = WriteLedger<Write>;

  [[nodiscard]] Exchange exchange(const Request& r) const;
  [[nodiscard]] std::optional<Request> run_request(Command c, std::int32_t rpm) const;
  // A write's part judged against the drive as `faulted` leaves it (a reset clears it).
  [[nodiscard]] WriteCheck judge(const WriteOp& op, bool& faulted) const;
  // accel_time's engineering value in accel's 100 ms units, where the frame carries it.
  static std::optional<std::uint16_t> accel_of(const Value& v);
  void apply_reply(const Reply& r);
  void settle_write(const Request& sent);

  std::uint8_t address_;
  Millis poll_interval_;
  Settings settings_;
  Writes writes_{completions_};
  bool setup_due_;               // settings_.accel_100ms is to be sent before anything else
  std::optional<Op> in_flight_;  // the op of the request on the line
  bool write_on_line_ = false;   // that request is writes_.front()'s
  TimePoint last_sent_{};
  std::optional<TimePoint> next_poll_;  // none: at once
};

}  // namespace drivegate::testdrive
