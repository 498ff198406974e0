// drivegated at run time: plugins, configuration, gateway, Modbus TCP server, signals and the
// systemd protocol, all on one io_context. SIGTERM / SIGINT stop the drives and exit 0; SIGHUP
// re-reads the configuration and swaps the gateway without dropping a Modbus connection (and
// applies the new [server] limits and listener policies, re-reading TLS files; a listener added,
// removed or moved waits for a restart), or keeps the running one when the new file is bad.
#pragma once

#include <spdlog/logger.h>

#include <boost/asio/io_context.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/asio/steady_timer.hpp>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "config/config.h"
#include "gateway/gateway.h"
#include "history/history.h"
#include "http/http_server.h"
#include "modbus/backend_switch.h"
#include "modbus/server.h"
#include "modbus/slave_listeners.h"
#include "mqtt/northbound.h"
#include "net/clock.h"
#include "plugin/plugins.h"
#include "status_content.h"
#include "systemd_notifier.h"
#include "trend_sampler.h"

namespace drivegate {

struct DaemonOptions {
  std::filesystem::path config;
  std::filesystem::path plugin_dir;     // empty: default_plugin_dir()
  std::optional<ListenAddress> listen;  // replaces the first listener's address
  std::filesystem::path state_dir;      // what survives a restart (the bdSeq); empty: nothing
};

class Daemon {
 public:
  Daemon(DaemonOptions options, std::shared_ptr<spdlog::logger> log);
  ~Daemon();
  // Runs until SIGTERM / SIGINT; returns the process exit code.
  int run();

 private:
  std::optional<Config> load_config();
  void wait_signal();
  // SIGHUP: reads the file and, once the devices it replaces settled their writes in flight
  // (finish_reload), puts the new gateway in place of the running one (swap_gateway).
  void reload();
  void finish_reload();
  void swap_gateway(Config next_config, std::unique_ptr<Gateway> next,
                    std::vector<std::string> restart);
  void shutdown();
  void restart_mqtt(const MqttConfig& next, Gateway& gateway);
  void tick_status();
  // Once a second: the trends sampled, the MQTT session's state, the audit's summaries due.
  void tick_trends();
  // The MQTT session's state, recorded in the history when it changes.
  void record_mqtt_state();
  void tick_watchdog();
  bool start_http();
  std::string status_line() const;

  DaemonOptions options_;
  std::shared_ptr<spdlog::logger> log_;
  // The network servers' time (net/clock.h). Declared before io_, so it outlives it: destroying
  // the io_context destroys the handlers it still holds, and with them acceptors and connections
  // whose timers detach from the clock as they go.
  net::SteadyClock clock_;
  // What happened and when (history/history.h), made as [history] says once and kept across
  // reloads. Declared before io_ and the gateway, so it outlives both: an old gateway a reload
  // left to a queued handler goes with io_, and its devices record here.
  std::unique_ptr<JournalWriter> journal_;
  std::unique_ptr<History> history_;
  std::unique_ptr<TrendSampler> sampler_;  // none with [history] trend_seconds = 0
  boost::asio::io_context io_;
  boost::asio::signal_set signals_;
  boost::asio::steady_timer status_timer_;
  boost::asio::steady_timer watchdog_timer_;
  boost::asio::steady_timer trend_timer_;
  boost::asio::steady_timer reload_timer_;
  SystemdNotifier notifier_;
  std::string mqtt_state_;
  PluginRegistry plugins_;
  Config config_;
  std::unique_ptr<Gateway> gateway_;
  BackendSwitch backend_;
  std::unique_ptr<modbus::Server> server_;
  std::unique_ptr<SlaveListeners> slaves_;  // the RTU / ASCII listeners (serial and TCP)
  std::unique_ptr<StatusContent> content_;
  std::unique_ptr<http::HttpServer> http_;
  std::unique_ptr<mqtt::Northbound> mqtt_;  // after gateway_: goes first, unhooking its devices
  bool stopping_ = false;
  // A reload read and built, waiting for the writes in flight at the devices it replaces.
  struct PendingReload {
    Config config;
    std::unique_ptr<Gateway> next;
    std::vector<std::string> restart;
    TimePoint give_up;  // then it goes on, whatever is still in flight
  };
  std::optional<PendingReload> pending_reload_;
  bool reload_again_ = false;  // a SIGHUP came meanwhile
  // What the configuration file says and only a restart applies (listeners added, removed or
  // moved, [http], [mqtt]): the status page and JSON show it.
  std::vector<std::string> restart_needed_;
};

}  // namespace drivegate
