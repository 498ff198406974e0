// One configured drive at run time: its driver, its place on the line (Link), its register image,
// the Modbus writes in flight and its PLC-loss failsafe. The bus engine drives it through the
// Station interface; every call it makes reaches the driver through here, so the device's state
// is published after each one without anyone having to remember to. The gateway reads and
// writes its registers.
//
//   device.cpp           the Station side: driver calls, comm_lost, ticks, logging of changes,
//                        what is done with a drive first found running (on_start)
//   device_image.cpp     the register image (common block and adapter points; register_image.h
//                        holds the tables) and reads
//   device_writes.cpp    Modbus write requests: validated, checked whole, queued (bounded, one
//                        write turn of the line per part), applied part by part, confirmed; the
//                        queue and its states are write_queue.h
//   device_failsafe.cpp  the PLC-loss failsafe (failsafe.h keeps its time, failsafe_enforcer.h
//                        decides what to write while it is latched)
//   device_history.cpp   what it records in the history: each write's audit record, its events
//                        (history_recorder.h keeps what was recorded last)
//   device_reload.cpp    a reload: the new device takes over the PLC's failsafe watchdog
#pragma once

#include <spdlog/logger.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "bus/station.h"
#include "config/config.h"
#include "gateway/failsafe.h"
#include "gateway/failsafe_enforcer.h"
#include "gateway/history_recorder.h"
#include "gateway/outcome.h"
#include "gateway/register_image.h"
#include "gateway/register_map.h"
#include "gateway/session.h"
#include "gateway/write_queue.h"
#include "history/history.h"
#include "net/log_throttle.h"

namespace drivegate {

// The access level a write to `point` needs (README, "Listeners and access"): the common
// command block (command, setpoint_rpm, heartbeat) and a point its adapter opened to operate
// (PointSpec::write_level) are operate's, every other writable point maintain's. Device::write
// and write_points deny less.
AccessLevel required_level(const MappedPoint& point);

class Device final : public Station {
 public:
  // `history` (may be null: nothing recorded) gets each write's audit record and the device's
  // events; it outlives the device.
  Device(DeviceConfig config, const AdapterDescriptor& adapter, std::unique_ptr<Driver> driver,
         std::shared_ptr<spdlog::logger> log, TimePoint now, History* history = nullptr);
  ~Device() override;
  Device(const Device&) = delete;
  Device& operator=(const Device&) = delete;

  [[nodiscard]] const DeviceConfig& config() const { return config_; }
  [[nodiscard]] const AdapterDescriptor& adapter() const { return adapter_; }
  [[nodiscard]] const RegisterMap& map() const { return map_; }
  // The driver's published state (read-only: every call into the driver goes through here).
  [[nodiscard]] const Driver& driver() const { return *driver_; }
  [[nodiscard]] const CommonState& state() const { return driver_->common(); }
  [[nodiscard]] const Link& line() const { return link_; }
  [[nodiscard]] bool online() const;
  [[nodiscard]] bool comm_lost() const { return link_.health.comm_lost(); }
  // The PLC-loss failsafe tripped and no run command was written since (StatusBit::failsafe).
  [[nodiscard]] bool failsafe_latched() const { return failsafe_.latched(); }

  // --- Station: the bus engine's side ---
  [[nodiscard]] const std::string& name() const override { return config_.name; }
  Link& link() override { return link_; }
  [[nodiscard]] PendingWrites pending_writes(TimePoint now) const override;
  void on_work(std::function<void()> kick) override { kick_ = std::move(kick); }
  std::optional<Exchange> next_exchange(TimePoint now, Turn turn) override;
  [[nodiscard]] TimePoint wake_at() const override { return driver_->wake_at(); }
  [[nodiscard]] std::optional<TimePoint> state_read_at(TimePoint now) const override {
    return traits_.state_in_parts ? driver_->state_read_at() : now;
  }
  RxVerdict on_receive(ByteView rx, TimePoint now) override;
  void on_no_reply(TimePoint now) override;
  void on_comm_lost(TimePoint now) override;
  void on_tick(TimePoint now) override;

  // `on_change` is called after each driver call and each write (the image may have changed):
  // the MQTT northbound samples the device then. One watcher; an empty function removes it.
  void watch(std::function<void()> on_change) { watcher_ = std::move(on_change); }

  // --- The northbounds' side (Modbus through the gateway, MQTT) ---
  // Fills `out` from the register image, 32-bit values in the session's word order; no_such_point
  // when any address of the range is unmapped. A read of the fault state tells the session's
  // FaultReads (fault_reads.h) what it showed.
  Outcome read(const Session& session, Table table, std::uint16_t address,
               std::span<std::uint16_t> out, TimePoint now);
  // A write request of registers (or bits) as a Modbus client sends it: validated against the
  // map, checked whole by the driver, then applied part by part; `done` gets the outcome once
  // every part settled, or the first failure. Any outcome but ok returned here means nothing of
  // the request was applied and `done` is not called. A point beyond the session's access level
  // is denied, checked with the map before the values, so it never reaches the driver; 32-bit
  // values are read in the session's word order.
  Outcome write(const Session& session, Table table, std::uint16_t address,
                std::span<const std::uint16_t> in, WriteDone done, TimePoint now);
  // One point of a write by name (an MQTT DCMD) and the engineering value it is to take.
  struct PointWrite {
    const MappedPoint* point;
    Value value;
  };
  // Points written as one request: each value is encoded into its point's registers as a client
  // in the map's word order would write it (a value those registers cannot hold is invalid), then
  // the registers are validated, judged whole, applied and confirmed exactly as write() does.
  Outcome write_points(const Session& session, std::span<const PointWrite> points, WriteDone done,
                       TimePoint now);
  // Whether every Modbus request for this device is forwarded to it as it is (pass-through,
  // Driver::forwards) rather than served from the register map.
  [[nodiscard]] bool forwards() const { return driver_->forwards(); }
  // A Modbus request PDU for a pass-through device: refused at once when it is not one whole,
  // well-formed request (invalid_value), when its function is one no client may forward or
  // needs more than the session's access (denied; forward_access.h), then queued and carried
  // out like a write (a bounded queue, reads in places of their own; write turns alternating
  // with the line's polls, the same deadline), sent as it is, and answered with the slave's
  // reply. Nothing but ok returned here calls `done`. Every refusal and every forwarded request
  // that may write is in the audit trail. It never feeds the failsafe: a pass-through device has
  // no command block.
  Outcome forward(const Session& session, std::span<const std::uint8_t> pdu, ForwardDone done,
                  TimePoint now);
  // A command from the gateway itself (shutdown, or on_start = stop: `source` says which),
  // outside Modbus: it neither feeds nor resets the failsafe. `done` is called exactly once.
  void command(Command c, WriteDone done, TimePoint now, SourceKind source = SourceKind::shutdown);
  // Shutdown has begun: from now on every client's write, from any northbound, is refused
  // (no_response) before it reaches the driver, so that nothing runs the motor after the shutdown
  // stop.
  void close_to_clients() { closed_to_clients_ = true; }
  // A reload is about to replace or remove this device and waits for its writes in flight to
  // settle with what the drive says (Gateway::hold_for_reload): until then a client's new write
  // is refused busy before it reaches the driver, but a stop and the heartbeat alone, which are
  // carried out as ever.
  void hold_for_reload() { held_for_reload_ = true; }
  [[nodiscard]] bool held_for_reload() const { return held_for_reload_; }
  // How long a write may take before it is failed unconfirmed (DriverTraits::write_timeout).
  [[nodiscard]] Millis write_timeout() const { return traits_.write_timeout; }
  // Fails every request in flight (shutdown, bus closed for good); `reason` for the audit trail.
  void fail_pending(Outcome why, TimePoint now, std::string_view reason = {});
  // A reload replaced `old` (the same name, other settings) by this device, not started yet: it
  // takes over what was promised to the PLC there (docs/safety.md, "A reload and the failsafe"):
  // the failsafe watchdog, armed with its deadline or latched (its action then sent again to
  // this driver), and the heartbeat register.
  void take_over(const Device& old);
  // Writes waiting or being carried out (status bit command_pending).
  [[nodiscard]] std::size_t writes_in_flight() const { return writes_.size(); }
  [[nodiscard]] const WriteStats& write_stats() const { return write_stats_; }
  // A request PDU as the audit trail says it: "pdu 10 00 01 ..." (at most 32 bytes shown).
  [[nodiscard]] static std::string describe_pdu(std::span<const std::uint8_t> pdu);

 private:
  enum class Origin : std::uint8_t { plc, gateway };
  // The gateway's own writes (shutdown, failsafe) may write anything, in the map's word order.
  static Session gateway_session(SourceKind source) {
    Session s{AccessLevel::maintain, WordOrder::big, false};
    s.source.kind = source;
    return s;
  }
  using Part = WritePart;
  using Request = WriteRequest;
  using Answer = WriteAnswer;  // whom a request answers and what it records
  enum class Progress : std::uint8_t { done, waiting, failed };

  // device.cpp
  // `always`: tell the watcher even when no write settled (the driver heard or missed a reply).
  void publish(TimePoint now, bool always = true);
  void log_changes();
  void first_contact();
  void stop_on_start(TimePoint now);
  // device_image.cpp
  void refresh_image(TimePoint now);
  void refresh_common(Table table, TimePoint now);
  // Whether the range holds a whole point of the fault state: status, fault_code, fault_mask
  // (both its words: either alone may read 0 with a fault shown), or the fault status bit.
  [[nodiscard]] bool shows_faults(Table table, std::uint16_t address, std::size_t n) const;
  // device_writes.cpp
  // Hands the oldest queued write's next parts to the driver, on a write turn or whenever the
  // device owes no poll (may_release); true if any part was applied.
  bool release(TimePoint now, bool write_turn);
  [[nodiscard]] bool may_release(TimePoint now) const;
  void next_request(TimePoint now);
  Outcome refuse_run_while_latched(const char* source, TimePoint now);
  void supersede_runs(TimePoint now);
  Outcome submit(const Session& session, Table table, std::uint16_t address,
                 std::span<const std::uint16_t> in, Answer& answer, TimePoint now, Origin origin);
  Outcome write_points_checked(const Session& session, std::span<const PointWrite> points,
                               Answer& answer, TimePoint now);
  Outcome validate(const Session& session, Table table, std::uint16_t address,
                   std::span<const std::uint16_t> in, std::vector<Part>& parts) const;
  Outcome enqueue(const Session& session, std::vector<Part> parts, Answer& answer, TimePoint now,
                  Origin origin);
  Outcome begin(Request& r, bool at_once, TimePoint now);
  Progress advance(Request& r, TimePoint now, Outcome& failure);
  Progress advance_forward(Request& r, TimePoint now, Outcome& failure);
  void settle(const Completion& c, TimePoint now);
  // `why`: what the audit record says beyond the outcome, if anything.
  void finish(const Request* r, Outcome outcome, TimePoint now, std::string_view why = {});
  void expire_requests(TimePoint now);
  // device_history.cpp
  [[nodiscard]] Answer answer_to(const Session& session, WriteDone done, std::string asked,
                                 TimePoint now) const;
  // The outcome a write entry returns: recorded here unless the request took the answer.
  Outcome answered(Answer& answer, Outcome outcome, TimePoint now);
  void record(Answer& answer, Outcome outcome, TimePoint now);
  [[nodiscard]] static std::string describe(std::span<const Part> parts);
  [[nodiscard]] static std::string value_text(const PointSpec& spec, const Value& value);
  // Tells the history recorder what the device shows now.
  void record_changes();
  // device_failsafe.cpp
  void failsafe_tick(TimePoint now);
  void enforce_failsafe(TimePoint now);
  void failsafe_settled(FailsafeAction action, Outcome outcome);

  DeviceConfig config_;
  const AdapterDescriptor& adapter_;
  std::unique_ptr<Driver> driver_;
  DriverTraits traits_;
  RegisterMap map_;
  std::shared_ptr<spdlog::logger> log_;
  Link link_;
  RegisterImage image_;  // what a PLC reads (register_image.h)
  std::uint16_t heartbeat_ = 0;

  WriteQueue writes_;  // the requests in flight and what the driver was handed (write_queue.h)
  bool closed_to_clients_ = false;
  bool held_for_reload_ = false;
  WriteStats write_stats_;
  net::LogThrottle refusal_log_;  // refusals any client can cause, per device
  std::function<void()> kick_;
  std::function<void()> watcher_;

  // PLC-loss failsafe (docs/safety.md): the watchdog's time, and what is done while it is latched.
  FailsafeWatchdog failsafe_;
  FailsafeEnforcer enforcer_;
  TimePoint last_tick_{};

  // What on_start does with a drive first found running (first_contact):
  //   unchecked --first contact--> checked, or stop_due (found running, on_start = stop)
  //   stop_due --the next tick sends the stop, or a client writes first--> checked
  enum class StartCheck : std::uint8_t { unchecked, stop_due, checked };
  StartCheck start_ = StartCheck::unchecked;

  // What was last logged, to log changes only.
  bool logged_online_ = false;
  FaultSet logged_faults_;
  HistoryRecorder recorder_;  // the events recorded in the history (history_recorder.h)
};

}  // namespace drivegate
