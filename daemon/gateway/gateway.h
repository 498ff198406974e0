// The gateway: every configured device and bus, served to the northbounds by unit id. Each Modbus
// unit id is one device. Reads come from the register image; writes go to the device's driver and
// are answered when the drive confirmed them. The Modbus server reaches it through
// modbus/backend_switch.h, which says its outcomes as Modbus exceptions.
#pragma once

#include <spdlog/logger.h>

#include <array>
#include <boost/asio/io_context.hpp>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "bus/bus.h"
#include "config/config.h"
#include "config/config_diff.h"
#include "device.h"
#include "gateway/outcome.h"
#include "gateway/session.h"
#include "plugin/plugins.h"

namespace drivegate {

// Creates a device's driver from its configuration; nullptr and `error` if the adapter refuses.
// `line`: the bus it is on (for DeviceEnv::char_time), or nullptr where no line is involved
// (printing the register map).
std::unique_ptr<Driver> make_driver(const DeviceConfig& cfg, const AdapterDescriptor& adapter,
                                    bool maintenance, std::string& error,
                                    const BusConfig* line = nullptr);

class Gateway {
 public:
  // Builds every device (drivers created, nothing opened yet). Returns nullptr and fills
  // `errors` when an adapter refuses its device. `history` (may be null: nothing recorded) gets
  // every write's audit record and the devices' events; it outlives the gateway.
  static std::unique_ptr<Gateway> build(boost::asio::io_context& io, const Config& config,
                                        const PluginRegistry& plugins,
                                        std::shared_ptr<spdlog::logger> log,
                                        std::vector<std::string>& errors, bool maintenance = false,
                                        History* history = nullptr);
  ~Gateway();
  Gateway(const Gateway&) = delete;
  Gateway& operator=(const Gateway&) = delete;

  // What a reload from `running` to this (new) gateway changes (config/config_diff.h), device
  // by device and bus by bus, each device with what its adapter read (a profile's content).
  [[nodiscard]] ConfigDiff changes_from(const Gateway& running) const;
  // For a reload to `next` (built, not started), before adopt(): every device of this (running)
  // gateway that `next` replaces or removes refuses new client writes from now on but stops and
  // the heartbeat (Device::hold_for_reload), so that its writes in flight settle with what its
  // drive says before it goes. Returns the longest write_timeout of those with writes in flight
  // (zero: none, nothing to wait for); held_writes() counts what is left.
  Millis hold_for_reload(const Gateway& next);
  [[nodiscard]] std::size_t held_writes() const;
  // For a reload, before start(): every device of this (new, not started) gateway whose settings
  // are unchanged in `old` (changes_from) is taken from `old` as it runs, in place of the fresh
  // one: driver, command in force, failsafe timer and latch, counters, writes in flight,
  // whatever else changes on its line. A changed device takes over the PLC's failsafe watchdog
  // from the one it replaces (Device::take_over). Every bus whose own settings are unchanged is
  // taken with its port open and gets this gateway's devices; the others start afresh when this
  // gateway starts, once the caller has stopped `old` (and with it their ports and the devices
  // left in it: removed or changed).
  void adopt(Gateway& old);

  void start();  // opens the buses and starts polling (kept buses poll on)
  void stop();   // closes the buses; pending writes fail (no_response)
  // Puts every running drive whose on_shutdown is stop in its stop state (on_shutdown = hold
  // leaves it) and calls `done` once they confirmed or `limit` passed. From then on every
  // client's write is refused (no_response). `now`: the time the stops are asked at.
  void stop_drives(Millis limit, TimePoint now, std::function<void()> done);

  // A read (Device::read) or a write (Device::write) at the device whose unit id is `unit`:
  // no_such_device where there is none. A write before start() or after stop() is no_response.
  Outcome read(const Session& session, std::uint8_t unit, Table table, std::uint16_t address,
               std::span<std::uint16_t> out);
  Outcome write(const Session& session, std::uint8_t unit, Table table, std::uint16_t address,
                std::span<const std::uint16_t> values, WriteDone done);
  // A write a northbound refused itself before asking (a read-only Modbus session's): recorded in
  // the audit trail as denied, with its PDU.
  void refused_write(const Session& session, std::uint8_t unit,
                     std::span<const std::uint8_t> request);
  // A broadcast write a serial listener with broadcast = false applied to no device: recorded
  // in the audit trail as refused, for that reason, with its PDU and no device.
  void refused_broadcast(const Session& session, std::span<const std::uint8_t> request);
  // A write another northbound refused itself before it reached a device's write path (a DCMD
  // the MQTT side could not take: retained by the broker, an unknown metric...): recorded in the
  // audit trail as `asked`, with `result` and `why`. `device`: null when it named none of ours.
  void refused_write(const Source& source, const Device* device, std::string asked, Outcome result,
                     std::string why);
  // Whether the device at `unit` is a pass-through one (Device::forwards); then every request
  // for it goes to forward() (Device::forward) instead of read() and write().
  [[nodiscard]] bool forwards(std::uint8_t unit) const;
  // Whether a device has `unit` as its unit id.
  [[nodiscard]] bool serves(std::uint8_t unit) const { return units_[unit] != nullptr; }
  Outcome forward(const Session& session, std::uint8_t unit, std::span<const std::uint8_t> pdu,
                  ForwardDone done);

  [[nodiscard]] std::size_t devices_online() const;
  [[nodiscard]] const std::vector<std::unique_ptr<Device>>& devices() const { return devices_; }
  [[nodiscard]] Device* find(std::string_view name) const;
  [[nodiscard]] std::size_t buses_open() const;
  [[nodiscard]] const std::vector<std::shared_ptr<Bus>>& buses() const { return buses_; }

 private:
  Gateway(boost::asio::io_context& io, std::shared_ptr<spdlog::logger> log, History* history);
  // A write refused before it reached a device (none at that unit, the gateway not running):
  // recorded, and returned.
  Outcome refuse(const Session& session, std::uint8_t unit, std::string asked, Outcome why);
  // The audit record of a write refused before it reached a device (`device`: the one at `unit`,
  // if any).
  void record_refusal(const Source& source, const Device* device, std::uint8_t unit,
                      std::string asked, Outcome result, std::string why);
  // The configuration as its devices and buses hold it (files_read filled in).
  [[nodiscard]] Config running_config() const;
  [[nodiscard]] std::vector<Device*> devices_on(const std::string& bus) const;
  [[nodiscard]] std::vector<Station*> stations_on(const std::string& bus) const;

  boost::asio::io_context& io_;
  std::shared_ptr<spdlog::logger> log_;
  History* history_;
  std::vector<std::unique_ptr<Device>> devices_;
  std::vector<std::shared_ptr<Bus>> buses_;
  std::array<Device*, 256> units_{};
  bool running_ = false;
};

}  // namespace drivegate
