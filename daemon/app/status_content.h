// The daemon's answer to the HTTP side (http/content.h): each document rendered, when asked, from
// the gateway running now (reloads swap it) and the Modbus server; and captures, a frame tap
// (capture/pcap_tap.h) on one of its buses; and the history (history/history.h).
#pragma once

#include <memory>

#include "gateway/gateway.h"
#include "history/history.h"
#include "history/history_json.h"
#include "http/content.h"
#include "http/http_server.h"
#include "modbus/server.h"
#include "modbus/slave_listeners.h"
#include "mqtt/northbound.h"
#include "status/status_view.h"

namespace drivegate {

class StatusContent final : public http::Content {
 public:
  // `gateway`, `mqtt`, `http` and `restart_needed` are the daemon's own, read at each request
  // (`mqtt` is empty without [mqtt]; `http` is set once the HTTP server that asks is built).
  StatusContent(const std::unique_ptr<Gateway>& gateway, const modbus::Server& server,
                const std::unique_ptr<mqtt::Northbound>& mqtt,
                const std::unique_ptr<http::HttpServer>& http,
                const std::vector<std::string>& restart_needed, const History& history,
                const std::unique_ptr<SlaveListeners>& serial);
  std::string status_json() override;
  std::shared_ptr<http::SlicedDocument> events_page(const http::EventsQuery& query) override;
  std::string trends_json(const http::TrendsQuery& query) override;
  std::string metrics() override;
  std::string regmap_json() override;
  bool has_bus(std::string_view name) override;
  std::unique_ptr<http::CaptureStream> start_capture(std::string_view name, std::size_t max_bytes,
                                                     std::function<void()> on_data) override;

 private:
  [[nodiscard]] StatusView view(mqtt::NorthboundStatus& mqtt) const;

  const std::unique_ptr<Gateway>& gateway_;
  const modbus::Server& server_;
  const std::unique_ptr<mqtt::Northbound>& mqtt_;
  const std::unique_ptr<http::HttpServer>& http_;
  const std::vector<std::string>& restart_needed_;
  const History& history_;
  const std::unique_ptr<SlaveListeners>& slaves_;  // empty until the daemon made them
  EventsPages events_pages_;  // GET /api/v1/events: each page rendered once per change of the log
  double started_unix_;
};

}  // namespace drivegate
