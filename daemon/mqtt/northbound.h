// The MQTT northbound: the gateway's devices published as a Sparkplug B edge node (docs/mqtt.md).
// It wires three things on the daemon's event loop: the broker session (mosquitto_client.h,
// reconnecting with back-off), the Sparkplug state machine (edge_node.h), and the gateway, whose
// devices it samples when they change (Device::watch) and whose write path a DCMD takes
// (Device::write_points: the same validation, access rules and confirmation as a Modbus write).
// Neither the buses nor the Modbus server ever wait on it.
#pragma once

#include <spdlog/logger.h>

#include <array>
#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "config/config.h"
#include "gateway/gateway.h"
#include "gateway/point_values.h"
#include "mqtt/bd_seq_file.h"
#include "mqtt/edge_node.h"
#include "mqtt/mosquitto_client.h"
#include "mqtt/northbound_status.h"
#include "mqtt/store_forward.h"
#include "net/log_throttle.h"

namespace drivegate::mqtt {

class Northbound final : private sparkplug::Sink {
 public:
  // `state_dir`: where the bdSeq is kept across restarts (mqtt/bd_seq_file.h; empty: it is not).
  // `previous_bd_seq`: the bdSeq of the northbound this one replaces at a reload, which goes
  // before the file's.
  Northbound(boost::asio::io_context& io, const MqttConfig& config, std::string version,
             std::shared_ptr<spdlog::logger> log, const std::filesystem::path& state_dir = {},
             std::optional<std::uint8_t> previous_bd_seq = std::nullopt);
  ~Northbound() override;
  Northbound(const Northbound&) = delete;
  Northbound& operator=(const Northbound&) = delete;

  // Publishes `gateway`'s devices (the first call connects). After a reload, the new gateway: a
  // changed device set is a rebirth.
  void use(Gateway& gateway);
  // A clean end: NDEATH published, then DISCONNECT; the devices are no longer watched.
  void stop();

  [[nodiscard]] NorthboundStatus status() const;

 private:
  struct Watched {
    Device* device;
    std::vector<const MappedPoint*> points;  // the device's metrics, in DeviceDef order
    std::vector<std::int32_t> metric_of;     // per map point: its metric, or -1 (not published)
    std::vector<PointValue> scratch;         // point_values() of the last sample
    std::optional<TimePoint> data_at;        // the drive's last reply with its state...
    std::uint64_t data_ms = 0;               // ... on the payload's clock (Unix ms)
  };

  [[nodiscard]] std::optional<std::uint8_t> last_bd_seq(std::optional<std::uint8_t> previous) const;
  void connect();
  // To the next of [mqtt] brokers, when there is more than one: whether it moved.
  bool next_broker();
  // The primary host is offline here: end the session, try again `delay` later (on the next
  // broker, if there is one).
  void leave_broker(Millis delay);
  // Births still waiting for the host here: the next broker, the longer the more of them fail.
  void walk_on();
  [[nodiscard]] const std::string& broker_url() const;
  void connect_after(Millis delay);  // a new attempt, after half of `delay` to all of it
  void connected();
  void lost(const std::string& why);
  // The session is over, however it ended: the edge node is told, the store keeps what the
  // broker did not confirm.
  void session_ended();
  void message(std::string_view topic, std::string_view payload, bool retained);
  void changed(std::size_t index, std::uint64_t generation);
  void flush();
  void schedule_tick();
  [[nodiscard]] sparkplug::Now now() const;
  [[nodiscard]] sparkplug::DeviceDef define(const Device& device, Watched& watched) const;
  [[nodiscard]] std::vector<sparkplug::MetricValue> sample(Watched& watched) const;

  // Sink
  bool publish(const std::string& topic, const sparkplug::Payload& payload) override;
  void drop_session() override;
  void host_offline_before_births() override;
  void write(std::size_t device, std::vector<sparkplug::PointCommand> points) override;
  void notice(sparkplug::Notice kind, std::string message) override;
  void refused(sparkplug::RefusedCommand command) override;
  // Who a DCMD comes from, as the audit trail says it.
  [[nodiscard]] Source source() const;
  void store(std::string_view device, const sparkplug::Payload& historical) override;
  void pace();  // every StoreForward::kReplayPeriod while there is a store
  void replay_step();
  void delivered(std::uint64_t up_to);  // the client's: the broker confirmed up to this message

  boost::asio::io_context& io_;
  MqttConfig config_;
  std::shared_ptr<spdlog::logger> log_;
  BdSeqFile bd_seq_file_;
  std::unique_ptr<StoreForward> store_;  // [mqtt] store_forward with a state directory
  sparkplug::EdgeNode edge_;
  MosquittoClient client_;
  boost::asio::steady_timer retry_timer_;
  boost::asio::steady_timer tick_timer_;
  boost::asio::steady_timer pace_timer_;
  boost::asio::steady_timer host_timer_;  // a primary host silent on this broker
  unsigned replay_budget_ = 0;            // records this replay period may still send
  bool replay_posted_ = false;            // a replay_step() is on its way
  unsigned paces_ = 0;  // of pace_timer_, for the once-a-second sync
  Gateway* gateway_ = nullptr;  // use()'s, until stop(): where refused DCMDs are audited
  std::vector<Watched> watched_;
  std::vector<bool> dirty_;
  bool flush_posted_ = false;
  std::uint64_t generation_ = 0;  // of watched_: a watcher from before a reload is ignored
  Millis backoff_{0};
  Millis walk_backoff_{0};         // between brokers while the primary host is offline on each
  std::minstd_rand random_{std::random_device{}()};  // spreads the retries (connect_after)
  std::size_t broker_ = 0;         // which of config_.brokers the next attempt uses
  std::size_t client_broker_ = 0;  // which one client_ is set up for
  bool stopping_ = false;
  bool started_ = false;
  bool bd_seq_save_failed_ = false;  // warned once until a save succeeds again
  NorthboundStatus status_;
  std::array<net::LogThrottle, sparkplug::kNoticeKinds> notice_log_;  // per kind
  std::shared_ptr<bool> alive_ = std::make_shared<bool>(true);        // for writes settling later
};

}  // namespace drivegate::mqtt
