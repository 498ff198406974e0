#include "gateway/gateway.h"

#include <algorithm>
#include <boost/asio/steady_timer.hpp>

#include "config/config_diff.h"
#include "gateway/forward_access.h"
#include "base/log_context.h"

namespace drivegate {

namespace asio = boost::asio;

std::unique_ptr<Driver> make_driver(const DeviceConfig& cfg, const AdapterDescriptor& adapter,
                                    bool maintenance, std::string& error, const BusConfig* line) {
  DeviceEnv env;
  env.name = cfg.name;
  env.address = cfg.address;
  env.poll_interval = cfg.poll_interval;
  env.options = cfg.options;
  env.maintenance = maintenance;
  if (line != nullptr) {
    env.char_time = character_time(line->baud, line->parity, line->data_bits, line->stop_bits);
    env.bus_line =
        LineDefaults{line->baud, line->parity, line->data_bits, line->stop_bits, line->echo};
  }
  std::string why;
  auto driver = adapter.create_driver(env, why);
  if (!driver) {
    error = cfg.name + ": adapter '" + adapter.id +
            "' refused the device: " + (why.empty() ? "no reason given" : why);
  }
  return driver;
}

Gateway::Gateway(asio::io_context& io, std::shared_ptr<spdlog::logger> log, History* history)
    : io_(io), log_(std::move(log)), history_(history) {}

Gateway::~Gateway() {
  stop();
}

std::unique_ptr<Gateway> Gateway::build(asio::io_context& io, const Config& config,
                                        const PluginRegistry& plugins,
                                        std::shared_ptr<spdlog::logger> log,
                                        std::vector<std::string>& errors, bool maintenance,
                                        History* history) {
  std::unique_ptr<Gateway> gw(new Gateway(io, log, history));
  const auto now = Clock::now();
  for (const auto& dc : config.devices) {
    const AdapterDescriptor* base = plugins.find(dc.adapter);
    if (base == nullptr) {
      errors.push_back(config.path.string() + ":" + std::to_string(dc.line) + ": device '" +
                       dc.name + "': adapter '" + dc.adapter + "' is not installed");
      continue;
    }
    // The device's own descriptor (a described protocol's: AdapterDescriptor::specialise).
    std::string why;
    const AdapterDescriptor* adapter = specialised(*base, dc.options, why);
    if (adapter == nullptr) {
      errors.push_back(config.path.string() + ":" + std::to_string(dc.line) + ": device '" +
                       dc.name + "': " + why);
      continue;
    }
    const auto bus = std::find_if(config.buses.begin(), config.buses.end(),
                                  [&](const BusConfig& b) { return b.name == dc.bus; });
    std::string error;
    auto driver =
        make_driver(dc, *adapter, maintenance, error, bus != config.buses.end() ? &*bus : nullptr);
    if (!driver) {
      errors.push_back(config.path.string() + ":" + std::to_string(dc.line) + ": device " + error);
      continue;
    }
    DeviceConfig with_files = dc;
    with_files.files_read = driver->files_read();  // a reload compares it (config_diff.h)
    try {
      gw->devices_.push_back(std::make_unique<Device>(
          std::move(with_files), *adapter, std::move(driver),
          context_logger(*log, {.device = dc.name, .bus = dc.bus, .unit = dc.unit_id}), now,
          history));
    } catch (const std::exception& e) {
      errors.push_back(config.path.string() + ":" + std::to_string(dc.line) + ": device '" +
                       dc.name + "': " + e.what());
      continue;
    }
    gw->units_[dc.unit_id] = gw->devices_.back().get();
  }
  if (!errors.empty()) return nullptr;
  for (const auto& bc : config.buses) {
    gw->buses_.push_back(std::make_shared<Bus>(
        io, bc, gw->stations_on(bc.name),
        context_logger(*log, {.device = "", .bus = bc.name, .unit = std::nullopt})));
  }
  return gw;
}

std::vector<Device*> Gateway::devices_on(const std::string& bus) const {
  std::vector<Device*> on_bus;
  for (const auto& d : devices_) {
    if (d->config().bus == bus) on_bus.push_back(d.get());
  }
  return on_bus;
}

std::vector<Station*> Gateway::stations_on(const std::string& bus) const {
  const auto devices = devices_on(bus);
  return {devices.begin(), devices.end()};
}

Config Gateway::running_config() const {
  Config c;
  for (const auto& d : devices_) c.devices.push_back(d->config());
  for (const auto& b : buses_) c.buses.push_back(b->config());
  return c;
}

ConfigDiff Gateway::changes_from(const Gateway& running) const {
  return diff_config(running.running_config(), running_config());
}

namespace {

bool listed(const std::vector<std::string>& names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

}  // namespace

Millis Gateway::hold_for_reload(const Gateway& next) {
  const ConfigDiff diff = next.changes_from(*this);
  Millis longest{0};
  for (const auto& d : devices_) {
    if (listed(diff.devices_kept, d->config().name)) continue;  // moves over, writes and all
    d->hold_for_reload();
    if (d->writes_in_flight() > 0) longest = std::max(longest, d->write_timeout());
  }
  return longest;
}

std::size_t Gateway::held_writes() const {
  std::size_t n = 0;
  for (const auto& d : devices_) {
    if (d->held_for_reload()) n += d->writes_in_flight();
  }
  return n;
}

void Gateway::adopt(Gateway& old) {
  const ConfigDiff diff = changes_from(old);
  // Devices: the running one in place of the fresh one wherever the settings are the same; a
  // changed one takes over the PLC's failsafe from the one it replaces. The fresh ones a running
  // one replaces go last, once no engine points to them.
  std::vector<std::unique_ptr<Device>> replaced;
  for (auto& fresh : devices_) {
    const auto running = std::find_if(old.devices_.begin(), old.devices_.end(), [&](const auto& d) {
      return d && d->config().name == fresh->config().name;
    });
    if (running == old.devices_.end()) continue;
    if (!listed(diff.devices_kept, fresh->config().name)) {
      fresh->take_over(**running);
      continue;
    }
    replaced.push_back(std::move(fresh));
    fresh = std::move(*running);
  }
  std::erase(old.devices_, nullptr);
  for (const auto& gone : old.devices_) {
    if (!listed(diff.devices_removed, gone->config().name)) continue;
    const bool owed_stop = gone->driver().owed().stop_after_trip;
    const bool runs = gone->state().running || is_run(gone->state().command);
    if (gone->failsafe_latched() || runs || owed_stop) {
      log_->warn("device {}: removed by the reload while {}: the gateway no longer watches it",
                 gone->config().name,
                 gone->failsafe_latched() ? "its failsafe is latched"
                 : owed_stop              ? "its drive is owed a stop after a trip"
                                          : "its drive runs");
    }
  }
  // Buses: the running one, port open, wherever its own settings are the same.
  for (auto& fresh_bus : buses_) {
    if (!listed(diff.buses_kept, fresh_bus->config().name)) continue;
    const auto running = std::find_if(old.buses_.begin(), old.buses_.end(), [&](const auto& b) {
      return b->config().name == fresh_bus->config().name;
    });
    if (running == old.buses_.end()) continue;
    fresh_bus = std::move(*running);  // the fresh bus, never started, goes first
    old.buses_.erase(running);
  }
  for (auto& b : buses_) b->replace_stations(stations_on(b->config().name));
  units_.fill(nullptr);
  for (const auto& d : devices_) units_[d->config().unit_id] = d.get();
}

void Gateway::start() {
  running_ = true;
  for (auto& b : buses_) b->start();
}

void Gateway::stop() {
  if (!running_) return;
  running_ = false;
  for (auto& b : buses_) b->stop();
  const auto now = Clock::now();
  for (auto& d : devices_) d->fail_pending(Outcome::no_response, now, "the gateway stopped");
}

void Gateway::stop_drives(Millis limit, TimePoint now, std::function<void()> done) {
  struct Waiter {
    int outstanding = 0;
    std::function<void()> done;
    asio::steady_timer timer;
    explicit Waiter(asio::io_context& io) : timer(io) {}
    void finish() {
      if (!done) return;
      timer.cancel();
      auto d = std::move(done);
      done = nullptr;
      d();
    }
  };
  auto waiter = std::make_shared<Waiter>(io_);
  waiter->done = std::move(done);
  // No client may start a drive once shutdown has begun (a run queued now would reach it after
  // the stop); the stops below drop the runs already queued.
  for (auto& d : devices_) d->close_to_clients();
  for (auto& d : devices_) {
    // A drive owed a stop after a trip (Driver::owed) may read stopped while its set value would
    // restart it once the fault clears, the daemon gone: it is stopped too; and so is one whose
    // command in force is a run though it does not turn (yet: still starting, or a tripped fan a
    // client ran with the fault shown, which turns once the fault clears).
    const bool owed = d->driver().owed().stop_after_trip;
    const bool commanded = is_run(d->state().command);
    if ((!d->state().running && !owed && !commanded) || d->comm_lost()) continue;
    if (d->config().on_shutdown == ShutdownAction::hold) {
      log_->info("device {}: left as it is for shutdown (on_shutdown = hold)", d->config().name);
      continue;
    }
    ++waiter->outstanding;
    log_->info("device {}: stopping for shutdown{}", d->config().name,
               owed ? " (a stop is owed to it after a trip)" : "");
    d->command(
        Command::stop,
        [waiter, name = d->config().name, log = log_](Outcome outcome) {
          if (outcome != Outcome::ok) {
            log->warn("device {}: stop not confirmed ({})", name, to_string(outcome));
          }
          if (--waiter->outstanding == 0) waiter->finish();
        },
        now);
  }
  if (waiter->outstanding == 0) {
    waiter->finish();
    return;
  }
  waiter->timer.expires_after(limit);
  waiter->timer.async_wait([waiter](const boost::system::error_code& ec) {
    if (!ec) waiter->finish();
  });
}

Outcome Gateway::read(const Session& session, std::uint8_t unit, Table table, std::uint16_t address,
                      std::span<std::uint16_t> out) {
  Device* d = units_[unit];
  if (d == nullptr) return Outcome::no_such_device;
  return d->read(session, table, address, out, Clock::now());
}

Outcome Gateway::write(const Session& session, std::uint8_t unit, Table table,
                       std::uint16_t address, std::span<const std::uint16_t> values,
                       WriteDone done) {
  Device* d = units_[unit];
  if (d == nullptr || !running_) {
    return refuse(session, unit, describe_registers(table, address, values),
                  d == nullptr ? Outcome::no_such_device : Outcome::no_response);
  }
  return d->write(session, table, address, values, std::move(done), Clock::now());
}

void Gateway::refused_write(const Session& session, std::uint8_t unit,
                            std::span<const std::uint8_t> request) {
  refuse(session, unit, Device::describe_pdu(request), Outcome::denied);
}

void Gateway::refused_broadcast(const Session& session, std::span<const std::uint8_t> request) {
  record_refusal(session.source, nullptr, 0, Device::describe_pdu(request), Outcome::refused,
                 "a broadcast, and the listener has broadcast = false");
}

void Gateway::refused_write(const Source& source, const Device* device, std::string asked,
                            Outcome result, std::string why) {
  record_refusal(source, device, device != nullptr ? device->config().unit_id : 0, std::move(asked),
                 result, std::move(why));
}

Outcome Gateway::refuse(const Session& session, std::uint8_t unit, std::string asked, Outcome why) {
  std::string more;
  if (why == Outcome::no_response) more = "the gateway is not running";
  if (why == Outcome::denied) more = "beyond access " + std::string(to_string(session.access));
  record_refusal(session.source, units_[unit], unit, std::move(asked), why, std::move(more));
  return why;
}

void Gateway::record_refusal(const Source& source, const Device* device, std::uint8_t unit,
                             std::string asked, Outcome result, std::string why) {
  if (history_ == nullptr) return;
  CommandRecord r;
  r.source = source;
  if (device != nullptr) r.device = device->config().name;
  r.unit = unit;
  r.points = std::move(asked);
  r.result = result;
  r.why = std::move(why);
  history_->audit().record(r, Clock::now());
}

bool Gateway::forwards(std::uint8_t unit) const {
  const Device* d = units_[unit];
  return d != nullptr && d->forwards();
}

Outcome Gateway::forward(const Session& session, std::uint8_t unit,
                         std::span<const std::uint8_t> pdu, ForwardDone done) {
  Device* d = units_[unit];
  if (d == nullptr) return Outcome::no_such_device;  // forwards(unit) said there is one
  if (!running_) {
    // A forwarded write is audited like any other; a forwarded read is not a write.
    const ForwardVerdict v = judge_forward(pdu, static_cast<std::uint8_t>(d->config().address));
    if (v.needs == AccessLevel::read && v.refusal == Outcome::ok) return Outcome::no_response;
    return refuse(session, unit, Device::describe_pdu(pdu), Outcome::no_response);
  }
  return d->forward(session, pdu, std::move(done), Clock::now());
}

std::size_t Gateway::devices_online() const {
  return static_cast<std::size_t>(
      std::count_if(devices_.begin(), devices_.end(), [](const auto& d) { return d->online(); }));
}

std::size_t Gateway::buses_open() const {
  return static_cast<std::size_t>(
      std::count_if(buses_.begin(), buses_.end(), [](const auto& b) { return b->is_open(); }));
}

Device* Gateway::find(std::string_view name) const {
  for (const auto& d : devices_) {
    if (d->config().name == name) return d.get();
  }
  return nullptr;
}

}  // namespace drivegate
