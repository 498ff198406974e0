// One configured drive at run time: its driver, its register image, its counters, its
// communication state and the Modbus writes waiting for it. The bus engine reports line events
// to it; the gateway reads and writes its registers.
#pragma once

#include <spdlog/logger.h>

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <span>
#include <vector>

#include "config/config.h"
#include "failsafe.h"
#include "modbus/backend.h"
#include "register_map.h"

namespace drivegate {

struct DeviceCounters {
  std::uint32_t frames_good = 0;
  std::uint32_t bad_checksum = 0;
  std::uint32_t timeouts = 0;
  std::uint32_t retries = 0;
  std::uint32_t nacks = 0;
  std::uint32_t foreign = 0;
  std::uint32_t noise_bytes = 0;
};

// Counters of the line a device is on, shown in every one of its devices' common block.
struct BusCounters {
  std::uint32_t exchanges = 0;
  std::uint32_t timeouts = 0;
  std::uint32_t retries = 0;
  std::uint32_t echo_errors = 0;  // our own bytes did not come back as sent
  std::uint32_t noise_bytes = 0;  // bytes nobody asked for
  std::uint32_t reopens = 0;
};

class Device {
 public:
  Device(DeviceConfig config, const AdapterDescriptor& adapter, std::unique_ptr<Driver> driver,
         std::shared_ptr<spdlog::logger> log, TimePoint now);

  [[nodiscard]] const DeviceConfig& config() const { return config_; }
  [[nodiscard]] const AdapterDescriptor& adapter() const { return adapter_; }
  [[nodiscard]] const RegisterMap& map() const { return map_; }
  [[nodiscard]] Driver& driver() { return *driver_; }
  [[nodiscard]] const DriverTraits& traits() const { return traits_; }
  DeviceCounters& counters() { return counters_; }

  // --- line events, from the bus engine ---
  void frame_good(TimePoint now);
  void turn_failed(TimePoint now);  // an exchange ended without a reply
  [[nodiscard]] bool comm_lost() const { return comm_lost_; }
  [[nodiscard]] bool online() const;
  [[nodiscard]] bool in_backoff(TimePoint now) const { return now < probe_at_; }
  [[nodiscard]] TimePoint probe_at() const { return probe_at_; }
  [[nodiscard]] bool has_pending_writes() const { return !pending_.empty(); }
  // The counters of the bus this device is on (owned by the bus, which outlives reads).
  void attach_bus(const BusCounters* counters) { bus_counters_ = counters; }
  // Called whenever a write is queued, so the bus can send it without waiting for a poll.
  void on_work(std::function<void()> kick) { kick_ = std::move(kick); }

  // Takes the driver's completions and refreshes the register image. Call after any driver call.
  void sync(TimePoint now);
  // Periodic (every 100 ms): comm_lost detection, write deadlines and the PLC-loss failsafe.
  void housekeeping(TimePoint now);
  // Fails every pending write (shutdown, bus closed for good).
  void fail_pending(modbus::Exception why);

  // --- Modbus side, from the gateway ---
  modbus::Exception read(Table table, std::uint16_t address, std::span<std::uint16_t> out,
                         TimePoint now);
  modbus::Exception write(Table table, std::uint16_t address, std::span<const std::uint16_t> in,
                          modbus::WriteDone done, TimePoint now);
  // A command from the gateway itself (shutdown, failsafe), outside Modbus: it neither feeds
  // nor resets the failsafe.
  void command(Command c, modbus::WriteDone done, TimePoint now);
  // The PLC-loss failsafe tripped and no run command was written since (StatusBit::failsafe).
  [[nodiscard]] bool failsafe_latched() const { return failsafe_.latched(); }

 private:
  struct Batch;  // one Modbus write request, possibly spanning several points
  struct Pending {
    std::shared_ptr<Batch> batch;
    TimePoint deadline;
  };
  struct PointWrite {
    const MappedPoint* point;
    Value value;
  };
  enum class Origin : std::uint8_t { plc, gateway };

  modbus::Exception apply(Table table, std::uint16_t address, std::span<const std::uint16_t> in,
                          modbus::WriteDone done, TimePoint now, Origin origin);
  void failsafe_tick(TimePoint now);
  void enforce_failsafe(TimePoint now);
  void failsafe_settled(FailsafeAction action, modbus::Exception e);

  modbus::Exception validate(Table table, std::uint16_t address, std::span<const std::uint16_t> in,
                             std::vector<PointWrite>& writes) const;
  WriteStatus submit(const PointWrite& w, Ticket t, TimePoint now);
  void settle(Ticket t, WriteResult r);
  void refresh_image(TimePoint now);
  void refresh_dynamic(TimePoint now);
  std::span<std::uint16_t> registers(Table t) { return image_[static_cast<int>(t)]; }
  void log_transitions();

  DeviceConfig config_;
  const AdapterDescriptor& adapter_;
  std::unique_ptr<Driver> driver_;
  DriverTraits traits_;
  RegisterMap map_;
  std::shared_ptr<spdlog::logger> log_;
  DeviceCounters counters_;
  const BusCounters* bus_counters_ = nullptr;
  std::vector<std::uint16_t> image_[4];

  TimePoint last_good_;
  bool ever_good_ = false;
  bool comm_lost_ = false;
  int failures_ = 0;  // consecutive turns without a reply
  TimePoint probe_at_{};
  std::uint16_t heartbeat_ = 0;

  // PLC-loss failsafe (docs/safety.md). `failsafe_now_` is the action in force since the trip:
  // the configured one, or stop when the drive refused quick_stop or the preset speed.
  FailsafeWatchdog failsafe_;
  FailsafeAction failsafe_now_ = FailsafeAction::stop;
  bool failsafe_busy_ = false;     // the action's write is in flight
  bool failsafe_done_ = false;     // the drive confirmed the action since the trip
  bool failsafe_gave_up_ = false;  // the drive cannot take a stop at all (exception 0x03)
  TimePoint failsafe_retry_at_{};
  TimePoint last_tick_{};

  Ticket next_ticket_ = 1;
  std::map<Ticket, Pending> pending_;
  std::vector<Completion> completions_;  // scratch, reused
  std::function<void()> kick_;

  // What was last logged, to log changes only.
  bool logged_online_ = false;
  FaultSet logged_faults_;
};

}  // namespace drivegate
