#include "status_content.h"

#include <algorithm>
#include <chrono>
#include <unordered_map>

#include "bus/bus.h"
#include "capture/pcap_tap.h"
#include "gateway/device.h"
#include "history/history_json.h"
#include "regmap/regmap_format.h"
#include "status/status_view.h"

namespace drivegate {

namespace {
double unix_now() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}
// A page of the history (history_json.h) as the HTTP side renders it, a slice at a time.
class SlicedPage final : public http::SlicedDocument {
 public:
  explicit SlicedPage(std::shared_ptr<EventsPage> page) : page_(std::move(page)) {}
  bool render_slice(std::size_t bytes) override { return page_->render(bytes); }
  [[nodiscard]] bool whole() const override { return page_->whole(); }
  [[nodiscard]] std::shared_ptr<const std::string> document() const override {
    return page_->json();
  }

 private:
  std::shared_ptr<EventsPage> page_;
};

// A capture of one bus: the tap is on the bus from construction to destruction. Holding the bus
// keeps it (and its engine) alive should a reload drop it meanwhile; it then just goes quiet.
class BusCapture final : public http::CaptureStream {
 public:
  BusCapture(std::shared_ptr<Bus> bus,
             std::unordered_map<const Station*, capture::StationInfo> stations,
             std::size_t max_bytes, std::function<void()> on_data)
      : bus_(std::move(bus)),
        tap_(std::move(stations), Clock::now(),
             std::chrono::duration_cast<std::chrono::microseconds>(
                 std::chrono::system_clock::now().time_since_epoch())
                 .count(),
             max_bytes, std::move(on_data)) {
    bus_->add_tap(&tap_);
  }
  ~BusCapture() override { bus_->remove_tap(&tap_); }
  BusCapture(const BusCapture&) = delete;
  BusCapture& operator=(const BusCapture&) = delete;

  std::string take() override { return tap_.take(); }
  [[nodiscard]] bool full() const override { return tap_.full(); }

 private:
  std::shared_ptr<Bus> bus_;
  capture::PcapTap tap_;
};

}  // namespace

StatusContent::StatusContent(const std::unique_ptr<Gateway>& gateway, const modbus::Server& server,
                             const std::unique_ptr<mqtt::Northbound>& mqtt,
                             const std::unique_ptr<http::HttpServer>& http,
                             const std::vector<std::string>& restart_needed,
                             const History& history,
                             const std::unique_ptr<SlaveListeners>& serial)
    : gateway_(gateway),
      server_(server),
      mqtt_(mqtt),
      http_(http),
      restart_needed_(restart_needed),
      history_(history),
      slaves_(serial),
      events_pages_(history.events()),
      started_unix_(unix_now()) {}

StatusView StatusContent::view(mqtt::NorthboundStatus& mqtt) const {
  StatusView v{.gateway = *gateway_,
               .server = server_,
               .version = DRIVEGATE_VERSION,
               .started_unix = started_unix_,
               .now_unix = unix_now()};
  v.restart_needed = &restart_needed_;
  v.commands = &history_.audit().counts();
  v.history = &history_.events();
  if (mqtt_) {
    mqtt = mqtt_->status();
    v.mqtt = &mqtt;
  }
  if (http_) {
    v.http = http_->stats();
    v.http_clients = http_->client_count();
  }
  if (slaves_) {
    for (const auto& l : slaves_->tcp()) {
      v.serial.push_back({.port = l->name(),
                          .framing = l->options().framing == modbus_serial::Framing::rtu ? "rtu"
                                                                                         : "ascii",
                          .access = l->policy().session.access,
                          .open = true,
                          .bytes_received = l->bytes_received(),
                          .reopens = 0,
                          .counters = l->counters()});
    }
    for (const auto& l : slaves_->serial()) {
      v.serial.push_back({.port = l->options().line.port,
                          .framing = l->options().framing == modbus_serial::Framing::rtu ? "rtu"
                                                                                         : "ascii",
                          .access = l->policy().session.access,
                          .open = l->open(),
                          .bytes_received = l->bytes_received(),
                          .reopens = l->reopens(),
                          .counters = l->counters()});
    }
  }
  return v;
}

std::string StatusContent::status_json() {
  mqtt::NorthboundStatus mqtt;
  return drivegate::status_json(view(mqtt));
}

std::string StatusContent::metrics() {
  mqtt::NorthboundStatus mqtt;
  return metrics_text(view(mqtt));
}

std::shared_ptr<http::SlicedDocument> StatusContent::events_page(const http::EventsQuery& query) {
  EventFilter f;
  if (!query.kind.empty()) {
    EventKind kind{};
    if (!parse_event_kind(query.kind, kind)) return nullptr;
    f.kind = kind;
  }
  f.device = query.device;
  f.since_ms = query.since_ms;
  f.after_seq = query.after;
  f.limit = query.limit;
  return std::make_shared<SlicedPage>(events_pages_.page(f));
}

std::string StatusContent::trends_json(const http::TrendsQuery& query) {
  return drivegate::trends_json(history_.trends(), {query.name, query.since_ms});
}

std::string StatusContent::regmap_json() {
  std::vector<DeviceRegisters> devices;
  for (const auto& d : gateway_->devices()) {
    devices.push_back({&d->config(), d->map(), d->forwards()});
  }
  // The listeners as they run: the bound port (the configured one may be 0) and the word order
  // in force since the last reload.
  std::vector<ServedOn> listeners;
  for (std::size_t i = 0; i < server_.listener_count(); ++i) {
    modbus::ListenerOptions o = server_.listener(i);
    o.port = server_.port(i);
    listeners.push_back({o.name(), o.policy.word_order});
  }
  // And the RTU / ASCII ones, each by the name it logs under (a serial one by its port).
  if (slaves_) {
    for (const auto& l : slaves_->serial()) {
      listeners.push_back({l->name(), l->policy().session.word_order});
    }
    for (const auto& l : slaves_->tcp()) {
      listeners.push_back({l->name(), l->policy().session.word_order});
    }
  }
  return format_regmap(devices, listeners, RegmapFormat::json);
}

bool StatusContent::has_bus(std::string_view name) {
  const auto& buses = gateway_->buses();
  return std::any_of(buses.begin(), buses.end(),
                     [&](const auto& b) { return b->config().name == name; });
}

std::unique_ptr<http::CaptureStream> StatusContent::start_capture(std::string_view name,
                                                                  std::size_t max_bytes,
                                                                  std::function<void()> on_data) {
  for (const auto& bus : gateway_->buses()) {
    if (bus->config().name != name) continue;
    std::unordered_map<const Station*, capture::StationInfo> stations;
    for (const Station* st : bus->stations()) {
      capture::StationInfo info;
      info.device = st->name();
      if (const Device* d = gateway_->find(st->name())) {
        // The device's descriptor's id: a described protocol's names it ("framed/NAME"), so
        // that the dissector knows which description decodes the frames.
        info.adapter = d->adapter().id;
        info.unit_id = d->config().unit_id;
      }
      stations.emplace(st, std::move(info));
    }
    return std::make_unique<BusCapture>(bus, std::move(stations), max_bytes, std::move(on_data));
  }
  return nullptr;
}

}  // namespace drivegate
