// The driver of a described device: one Driver on the existing API that carries out any
// description (description.h), so the bus engine, the write queue, the failsafe and every
// northbound treat it exactly as a compiled adapter's.
//
//   driver.cpp         what the driver sends by itself (the handshake, the poll), what comes back,
//                      and the unified block
//   driver_writes.cpp  check() and apply(): commands, the setpoint and point writes, carried out
//                      by the description's messages and confirmed by its rules, on the shared
//                      bookkeeping of writes (drivegate/write_ledger.h)
#pragma once

#include <memory>
#include <optional>
#include <vector>

#include "codec.h"
#include "description.h"
#include "drivegate/driver_base.h"
#include "drivegate/write_ledger.h"
#include "state.h"

namespace drivegate::framed {

class FramedDriver final : public DriverBase {
 public:
  FramedDriver(std::shared_ptr<const Description> d, const DeviceEnv& env);

  DRIVEGATE_DRIVER_OVERRIDES;

 private:
  // A write on its way: what it changes, and once chosen, how it is carried out.
  struct Job {
    enum class Kind : std::uint8_t { command, setpoint, point };
    Kind kind = Kind::command;
    Command command = Command::stop;
    double rpm = 0;
    std::size_t point = 0;
    double value = 0;
    std::optional<std::size_t> rule;  // the point's on_write rule
    // Chosen when it first reaches the line, from what is in force then.
    const Alternative* alt = nullptr;
    std::optional<std::size_t> message;
    bool awaiting_state = false;  // sent; confirmed by `until` on the device's state
  };
  using Writes = WriteLedger<Job>;
  enum class Sent : std::uint8_t { init, poll, write };
  struct InFlight {
    Sent what = Sent::poll;
    std::size_t message = 0;
  };

  // driver.cpp
  [[nodiscard]] bool ready() const;
  [[nodiscard]] Millis poll_period() const;
  Exchange exchange(std::size_t message, const std::vector<Val>& vars, Sent what, TimePoint now,
                    std::optional<TimePoint> deadline);
  [[nodiscard]] bool answers(const Message& reply, const Frame& f) const;
  void refresh(TimePoint now);
  void publish();
  // driver_writes.cpp
  struct Judged {
    WriteCheck verdict = WriteCheck::ok;
    const Alternative* alt = nullptr;
  };
  [[nodiscard]] Judged judge(const WriteOp& op, std::vector<Val>& vars) const;
  [[nodiscard]] const Alternative* alternative(Command c, const std::vector<Val>& vars) const;
  [[nodiscard]] std::optional<std::size_t> on_write_rule(std::size_t point, double value) const;
  void propose(const Job& j, std::vector<Val>& vars) const;
  void put_in_force(const Job& j);
  [[nodiscard]] bool run_on_its_way() const;
  std::optional<Exchange> next_write(TimePoint now);
  void on_reply_to_write(const Frame& f);
  void confirm_by_state();
  void settled(const Writes::Entry& e, WriteResult r);
  [[nodiscard]] std::vector<Val> line_state() const;

  std::shared_ptr<const Description> d_;
  Codec codec_;
  State state_;
  Millis poll_interval_;
  DriverTraits traits_;
  std::uint8_t attempts_ = 3;
  Millis reply_timeout_{100};
  Millis confirm_{2500};
  std::chrono::nanoseconds char_time_{0};

  std::optional<InFlight> in_flight_;
  std::array<double, kMaxFields> sent_values_{};
  std::vector<double> sent_;    // the request in flight by global field id
  std::vector<double> fields_;  // the frame at hand by global field id
  TimePoint next_init_{};
  TimePoint next_poll_{};
  bool was_ready_ = false;
  bool poll_now_ = false;  // a write that went out failed: tell the device what is in force
  Writes writes_;
};

}  // namespace drivegate::framed
