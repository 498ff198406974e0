// drivegate dcmd: a Sparkplug B device command (DCMD) to a device of the running daemon, through
// the broker of its configuration, and the command's result as the edge node publishes it
// (docs/mqtt.md, "Commands"). The payload is encoded with the daemon's own codec
// (mqtt/sparkplug_codec.h); the session is the daemon's own MQTT client (mqtt/mosquitto_client.h),
// on this command's event loop, with a client id of its own and no will.
#include <unistd.h>

#include <algorithm>
#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>
#include <chrono>
#include <iostream>

#include "app/logging.h"
#include "commands.h"
#include "dcmd_metrics.h"
#include "gateway/gateway.h"
#include "mqtt/edge_node.h"
#include "mqtt/northbound.h"
#include "mqtt/sparkplug_codec.h"

namespace drivegate::cli {

namespace asio = boost::asio;

namespace {

constexpr Option kDcmdOptions[] = {
    kConfigOption,
    kDeviceOption,
    {"timeout-ms", 't', "N",
     "how long to wait for the broker and then for the command's result (1..3600000 ms, "
     "default 10000)"},
    kPluginDirOption,
    kHelpOption,
};

// One command's session: connect (each broker of [mqtt] in turn until one takes it), subscribe
// to the device's DDATA, publish the DCMD, and wait for the DDATA that reports its result.
class DcmdRun {
 public:
  DcmdRun(asio::io_context& io, const MqttConfig& mqtt, std::string device, std::string payload,
          std::string points, std::chrono::milliseconds timeout)
      : io_(io),
        mqtt_(mqtt),
        device_(std::move(device)),
        payload_(std::move(payload)),
        points_(std::move(points)),
        timeout_(timeout),
        timer_(io),
        client_(io, options(0),
                mqtt::MosquittoClient::Handlers{
                    [this] { connected(); },
                    [this](std::string why) { lost(std::move(why)); },
                    [this](std::string_view t, std::string_view p, bool) { message(t, p); },
                    {}},  // what the broker received: a DCMD waits for its result instead
                make_logger("drivegate", spdlog::level::warn)) {}

  void start() {
    timer_.expires_after(timeout_);
    timer_.async_wait([this](const boost::system::error_code& ec) {
      if (ec) return;
      const std::string ms = std::to_string(timeout_.count()) + " ms";
      done(false, sent_ ? "no result within " + ms
                        : "no broker session within " + ms +
                              (failures_.empty() ? std::string() : " (" + failures_ + ")"));
    });
    client_.connect("", "");
  }
  [[nodiscard]] bool ok() const { return ok_; }
  // Whether the edge node's result came (ok or not), and the command went out.
  [[nodiscard]] bool answered() const { return answered_; }
  [[nodiscard]] bool sent() const { return sent_; }
  [[nodiscard]] const std::string& said() const { return said_; }
  [[nodiscard]] const std::string& broker() const { return mqtt_.brokers.at(broker_).url; }

 private:
  // The edge node's broker settings, under a client id of this command's own: the broker would
  // end the daemon's session for a second client with its id.
  mqtt::BrokerOptions options(std::size_t index) const {
    auto o = mqtt::broker_options(mqtt_, index);
    o.client_id = "drivegate-dcmd-" + mqtt_.edge_node_id + "-" + std::to_string(::getpid());
    return o;
  }

  void connected() {
    // The broker takes a client's packets in order: the subscription is in place before the
    // command reaches the edge node, so its result cannot go by unseen.
    client_.subscribe(sparkplug::topic(mqtt_.group_id, sparkplug::MessageType::ddata,
                                       mqtt_.edge_node_id, device_),
                      1);
    sent_ = client_.publish(
        sparkplug::topic(mqtt_.group_id, sparkplug::MessageType::dcmd, mqtt_.edge_node_id, device_),
        payload_, 0, false);
    if (!sent_) done(false, "the broker session ended before the command could be sent");
  }

  void lost(std::string why) {
    if (finished_) return;
    if (sent_) {
      done(false, "the broker session ended before the result came: " + why);
      return;
    }
    failures_ += (failures_.empty() ? "" : "; ") + broker() + ": " + why;
    if (broker_ + 1 >= mqtt_.brokers.size()) {
      done(false, "cannot reach the broker: " + failures_);
      return;
    }
    ++broker_;
    client_.use_broker(options(broker_));
    client_.connect("", "");
  }

  void message(std::string_view topic, std::string_view payload) {
    const auto t = sparkplug::parse_topic(topic);
    if (!t || t->type != sparkplug::MessageType::ddata || t->device != device_) return;
    std::string why;
    const auto p = sparkplug::decode(payload, why);
    if (!p) return;
    if (const auto result = result_of(*p, points_)) {
      answered_ = true;
      done(*result == "ok", *result);
    }
  }

  // Out of libmosquitto's callback first: the session ends cleanly (DISCONNECT), then the loop.
  void done(bool ok, std::string said) {
    if (finished_) return;
    finished_ = true;
    ok_ = ok;
    said_ = std::move(said);
    timer_.cancel();
    asio::post(io_, [this] {
      client_.disconnect();
      io_.stop();
    });
  }

  asio::io_context& io_;
  const MqttConfig& mqtt_;
  std::string device_;
  std::string payload_;
  std::string points_;
  std::chrono::milliseconds timeout_;
  asio::steady_timer timer_;
  mqtt::MosquittoClient client_;
  std::size_t broker_ = 0;
  std::string failures_;
  bool sent_ = false;
  bool answered_ = false;
  bool finished_ = false;
  bool ok_ = false;
  std::string said_;
};

}  // namespace

int dcmd(std::span<const std::string> args) {
  const CommandLine cli(
      "drivegate dcmd", kDcmdOptions, {"-c FILE -d NAME [-t N] [-p DIR] METRIC=VALUE..."},
      "Sends a Sparkplug B DCMD writing the metrics to device NAME of the running daemon, through\n"
      "the broker, group_id and edge_node_id of FILE's [mqtt] (commands = true), and prints the\n"
      "result the edge node publishes (Command/Last Result). VALUE is a number, true or false,\n"
      "or one of the point's labels (command=run_forward). Exit status 0 when the result is ok.");
  int exit_status = 0;
  const auto parsed = parse_command(cli, args, exit_status);
  if (!parsed) return exit_status;
  const auto job = device_command(cli, *parsed, "METRIC=VALUE", exit_status);
  if (!job) return exit_status;
  const Config& config = job->config;
  const PluginRegistry& plugins = job->plugins;
  const DeviceArgs* device = &job->device;
  const std::vector<Assignment>& writes = job->writes;
  const std::string file = device->config.string();
  if (!config.mqtt.enabled) {
    std::cerr << "drivegate dcmd: " << file
              << " has no [mqtt]: the daemon is no Sparkplug edge node (docs/mqtt.md)\n";
    return 1;
  }
  if (!config.mqtt.commands) {
    std::cerr << "drivegate dcmd: " << file
              << " says [mqtt] commands = false: the edge node refuses every DCMD (set commands "
                 "= true and reload it: docs/mqtt.md)\n";
    return 1;
  }
  const auto dc = std::find_if(config.devices.begin(), config.devices.end(),
                               [&](const DeviceConfig& d) { return d.name == device->name; });
  if (dc == config.devices.end()) {
    std::cerr << "drivegate dcmd: no device '" << device->name << "' in " << file << "\n";
    return 1;
  }
  std::string error;
  const auto driver = make_driver(*dc, *plugins.find(dc->adapter), false, error);
  if (!driver) {
    std::cerr << file << ":" << dc->line << ": device " << error << "\n";
    return 1;
  }
  const RegisterMap map(driver->points());
  sparkplug::Payload payload;
  payload.timestamp =
      static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::milliseconds>(
                                     std::chrono::system_clock::now().time_since_epoch())
                                     .count());
  std::string points;
  for (const Assignment& w : writes) {
    const MappedPoint* p = map.find(w.point);
    auto metric = command_metric(w, p != nullptr ? &p->spec : nullptr, error);
    if (!metric) {
      std::cerr << "drivegate dcmd: " << error << "\n";
      return 1;
    }
    points += (points.empty() ? "" : ",") + w.point;
    payload.metrics.push_back(std::move(*metric));
  }

  asio::io_context io;
  DcmdRun run(io, config.mqtt, device->name, sparkplug::encode(payload), points, device->timeout);
  run.start();
  io.run();
  if (run.answered()) {
    std::cout << device->name << ": " << points << ": " << run.said() << "\n";
    return run.ok() ? 0 : 1;
  }
  std::cerr << "drivegate dcmd: " << device->name << ": " << points << ": " << run.said();
  if (run.sent()) {
    std::cerr << " from edge node " << config.mqtt.group_id << "/" << config.mqtt.edge_node_id
              << " on " << run.broker()
              << ": is drivegated connected to this broker, the device born (a comm_lost one "
                 "answers nothing), the edge node born there (with a primary_host, that host "
                 "online), and may this client publish DCMDs there?";
  }
  std::cerr << "\n";
  return 1;
}

}  // namespace drivegate::cli
