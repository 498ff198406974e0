#include "daemon.h"

#include <fmt/ranges.h>

#include <algorithm>
#include <boost/asio/post.hpp>
#include <csignal>
#include <string>
#include <vector>

#include "app/logging.h"
#include "config/config_diff.h"
#include "config/config_loader.h"
#include "modbus/options_from_config.h"

namespace drivegate {

namespace asio = boost::asio;

namespace {
constexpr Millis kStopLimit{3000};  // longest wait for drives to confirm stop on shutdown
constexpr Millis kStatusPeriod{2000};
// A reload waiting for writes in flight: how often it looks, and how long past their deadlines
// it waits at most (the device's housekeeping tick fails a write at its deadline).
constexpr Millis kReloadSettleCheck{10};
constexpr Millis kReloadSettleMargin{500};

// What a reload did to the devices and buses: one line for each change, with why (the log has
// each, the history all of them in one entry).
std::vector<std::string> diff_lines(const ConfigDiff& d) {
  std::vector<std::string> out;
  for (const auto& b : d.buses_reopened) {
    out.push_back(fmt::format("bus {} reopened: {}", b.name, fmt::join(b.what, ", ")));
  }
  for (const auto& b : d.buses_added) out.push_back(fmt::format("bus {} added", b));
  for (const auto& b : d.buses_removed)
    out.push_back(fmt::format("bus {} removed (port closed)", b));
  for (const auto& c : d.devices_changed) {
    out.push_back(
        fmt::format("device {} changed ({}): started afresh", c.name, fmt::join(c.what, ", ")));
  }
  for (const auto& n : d.devices_added) out.push_back(fmt::format("device {} added", n));
  for (const auto& n : d.devices_removed) out.push_back(fmt::format("device {} removed", n));
  return out;
}

}  // namespace

Daemon::Daemon(DaemonOptions options, std::shared_ptr<spdlog::logger> log)
    : options_(std::move(options)),
      log_(std::move(log)),
      journal_(make_journal_writer(log_)),
      signals_(io_, SIGINT, SIGTERM, SIGHUP),
      status_timer_(io_),
      watchdog_timer_(io_),
      trend_timer_(io_),
      reload_timer_(io_) {}

Daemon::~Daemon() {
  mqtt_.reset();
  if (http_) http_->close();
  if (gateway_) gateway_->stop();
  if (server_) server_->close();
}

bool Daemon::start_http() {
  if (!config_.http.enabled) return true;
  content_ = std::make_unique<StatusContent>(gateway_, *server_, mqtt_, http_, restart_needed_,
                                             *history_, slaves_);
  http::HttpOptions o;
  o.host = config_.http.listen.host;
  o.port = config_.http.listen.port;
  o.allow = config_.http.allow;
  o.capture = config_.http.capture;
  o.requests = net::RateLimit::per_second_in_bursts_of_two(config_.http.requests_per_s);
  http_ = std::make_unique<http::HttpServer>(io_, clock_, *content_, o, log_);
  if (const auto ec = http_->listen()) {
    log_->critical("cannot serve HTTP on {}:{}: {}", o.host, o.port, ec.message());
    return false;
  }
  return true;
}

std::optional<Config> Daemon::load_config() {
  auto result = drivegate::load_config(options_.config, plugins_);
  for (const auto& e : result.errors) log_->error("{}", e);
  if (result.config && options_.listen) {
    // --listen moves the first listener on a network address (a serial one has none).
    auto& ls = result.config->listeners;
    const auto network =
        std::find_if(ls.begin(), ls.end(), [](const ListenerConfig& l) { return !l.serial; });
    if (network != ls.end()) {
      auto& first = *network;
      // The file's warning about that listener's address no longer applies: --listen moved it.
      const std::string moved = listener_name(*network) + " lets";
      std::erase_if(result.warnings,
                    [&](const std::string& w) { return w.find(moved) != std::string::npos; });
      first.host = options_.listen->host;
      first.port = options_.listen->port;
    }
  }
  if (result.config) {
    for (const auto& w : result.warnings) log_->warn("{}", w);
  }
  return std::move(result.config);
}

int Daemon::run() {
  const auto dir = options_.plugin_dir.empty() ? default_plugin_dir() : options_.plugin_dir;
  for (const auto& refused : plugins_.load_directory(dir)) log_->error("plugin {}", refused);
  log_->info("adapters from {}: {}", dir.string(), plugins_.ids());

  auto config = load_config();
  if (!config) {
    log_->critical("{}: configuration refused, not starting", options_.config.string());
    return 1;
  }
  config_ = std::move(*config);
  history_ = std::make_unique<History>(
      HistoryBounds{config_.history.events, config_.history.commands, config_.history.refusals},
      &EventLog::system_ms, journal_.get(), config_.history.trend_seconds);
  if (config_.history.trend_seconds > 0) {
    sampler_ = std::make_unique<TrendSampler>(history_->trends());
  }
  std::vector<std::string> errors;
  gateway_ = Gateway::build(io_, config_, plugins_, log_, errors, false, history_.get());
  for (const auto& e : errors) log_->error("{}", e);
  if (!gateway_) return 1;

  auto so = modbus::server_options(config_);
  so.identity.product = "drivegate Modbus TCP gateway";
  so.identity.version = DRIVEGATE_VERSION;
  server_ = std::make_unique<modbus::Server>(io_, clock_, backend_, so, log_);
  if (const auto ec = server_->listen()) {  // the server logged which listener, and why
    log_->critical("Modbus TCP server not started: {}", ec.message());
    return 1;
  }
  if (!start_http()) return 1;
  gateway_->start();
  backend_.set(gateway_.get());
  modbus::DeviceIdentity serial_identity = so.identity;
  serial_identity.product = "drivegate Modbus gateway";
  slaves_ = std::make_unique<SlaveListeners>(io_, clock_, backend_, serial_identity, config_.server,
                                             log_);
  if (!slaves_->start(config_.listeners)) {  // it logged which listener, and why
    log_->critical("Modbus RTU / ASCII listener not started");
    return 1;
  }
  if (config_.mqtt.enabled) {
    mqtt_ = std::make_unique<mqtt::Northbound>(io_, config_.mqtt, DRIVEGATE_VERSION, log_,
                                               options_.state_dir);
    mqtt_->use(*gateway_);
  }
  if (server_->listener_count() > 0) {
    log_->info("serving {} devices on {} buses, Modbus TCP on {} listener(s), the first on port {}",
               gateway_->devices().size(), config_.buses.size(), server_->listener_count(),
               server_->port());
  } else {
    log_->info("serving {} devices on {} buses, no Modbus TCP listener", gateway_->devices().size(),
               config_.buses.size());
  }
  for (const auto& s : slaves_->serial()) {
    history_->record(EventKind::listener, "", 0,
                     fmt::format("Modbus listener {} started", s->name()),
                     {{"listener", s->name()}, {"state", "open"}});
  }
  for (const auto& t : slaves_->tcp()) {
    history_->record(EventKind::listener, "", 0,
                     fmt::format("Modbus listener {} open on port {}", t->name(), t->port()),
                     {{"listener", t->name()}, {"state", "open"}});
  }
  for (std::size_t i = 0; i < server_->listener_count(); ++i) {
    history_->record(EventKind::listener, "", 0,
                     fmt::format("Modbus listener {} open on port {}", server_->listener(i).name(),
                                 server_->port(i)),
                     {{"listener", server_->listener(i).name()}, {"state", "open"}});
  }
  wait_signal();
  notifier_.ready(status_line());
  tick_status();
  tick_watchdog();
  tick_trends();
  io_.run();
  // Whatever was folded is said before the daemon goes: no write is left uncounted.
  history_->audit().flush(Clock::now(), /*all=*/true);
  log_->info("stopped");
  return 0;
}

void Daemon::wait_signal() {
  signals_.async_wait([this](const boost::system::error_code& ec, int signo) {
    if (ec) return;
    if (signo == SIGHUP) {
      reload();
      wait_signal();
      return;
    }
    log_->info("signal {}: shutting down", signo == SIGTERM ? "SIGTERM" : "SIGINT");
    shutdown();
  });
}

void Daemon::reload() {
  if (pending_reload_) {
    // The last one still waits for writes to settle: this file is read once it is applied.
    log_->info("SIGHUP: the configuration is read again once the reload under way is applied");
    reload_again_ = true;
    return;
  }
  notifier_.reloading();
  log_->info("SIGHUP: re-reading {}", options_.config.string());
  auto config = load_config();
  // What this reload applies now and what waits for a restart (config/config_diff.h).
  const ReloadPlan plan = config ? plan_reload(config_, *config) : ReloadPlan{};
  std::vector<std::string> errors;
  std::unique_ptr<Gateway> next;
  if (config) next = Gateway::build(io_, *config, plugins_, log_, errors, false, history_.get());
  for (const auto& e : errors) log_->error("{}", e);
  // The listeners' new policies, TLS files re-read; nothing changes if any of it fails.
  std::vector<std::string> restart;
  if (next) {
    const auto listeners = server_->reload_listeners(modbus::tcp_listeners(config->listeners));
    for (const auto& e : listeners.errors) log_->error("listener {}", e);
    if (!listeners.errors.empty()) next.reset();
    auto restart_listeners = plan.tcp_listeners_restart;
    if (next) {  // nothing changes otherwise
      slaves_->reload(config->listeners);
      restart_listeners.insert(restart_listeners.end(), plan.serial_listeners_restart.begin(),
                               plan.serial_listeners_restart.end());
    }
    for (const auto& l : restart_listeners) {
      log_->warn("listener {}: takes effect at the next restart (listening sockets are bound once)",
                 l);
      restart.push_back("listener " + l);
      history_->record(EventKind::listener, "", 0,
                       "listener " + l + ": takes effect at the next restart",
                       {{"listener", l}, {"state", "restart needed"}});
    }
    if (next) {
      for (const auto& c : plan.listener_policies) {
        log_->info("reload: listener {}: {} (open connections take it at once)", c.name,
                   fmt::join(c.what, ", "));
      }
    }
  }
  if (!next) {
    log_->error("new configuration refused: still running the previous one");
    std::string why = errors.empty() ? std::string("see the journal") : errors.front();
    history_->record(EventKind::reload, "", 0,
                     "reload refused, still running the previous configuration: " + why,
                     {{"result", "refused"}, {"why", why}});
    notifier_.ready(status_line());
    return;
  }
  if (!plan.server_limits.empty()) {
    server_->set_limits(modbus::server_limits(config->server));
    log_->info("[server] applied without closing a connection: {}",
               fmt::join(plan.server_limits, ", "));
  }
  for (const auto& section : plan.sections_restart) {
    log_->warn("{} changes take effect at the next restart", section);
    restart.push_back(section);
  }
  plan.keep_what_waits(config_, *config);
  // A device the new configuration replaces or removes first settles the writes it has in
  // flight, each with what its drive says (docs/safety.md, section 2): the swap waits for them,
  // at most until the deadline of a write in flight and of a stop sent meanwhile.
  const Millis wait = gateway_->hold_for_reload(*next);
  if (wait > Millis(0)) {
    log_->info("reload: waiting for the writes in flight at the devices it replaces");
  }
  pending_reload_ = PendingReload{std::move(*config), std::move(next), std::move(restart),
                                  Clock::now() + 2 * wait + kReloadSettleMargin};
  finish_reload();
}

void Daemon::finish_reload() {
  if (!pending_reload_ || stopping_) return;
  if (gateway_->held_writes() > 0 && Clock::now() < pending_reload_->give_up) {
    reload_timer_.expires_after(kReloadSettleCheck);
    reload_timer_.async_wait([this](const boost::system::error_code& ec) {
      if (!ec) finish_reload();
    });
    return;
  }
  PendingReload pending = std::move(*pending_reload_);
  pending_reload_.reset();
  swap_gateway(std::move(pending.config), std::move(pending.next), std::move(pending.restart));
  if (reload_again_) {
    reload_again_ = false;
    reload();
  }
}

void Daemon::swap_gateway(Config next_config, std::unique_ptr<Gateway> next,
                          std::vector<std::string> restart) {
  const bool mqtt_reconfigured = plan_reload(config_, next_config).mqtt_session;
  // Unchanged devices and buses move over running; the changed buses close before the new ones
  // open their ports.
  const ConfigDiff diff = next->changes_from(*gateway_);  // profiles' content included
  next->adopt(*gateway_);
  gateway_->stop();
  next->start();
  backend_.set(next.get());
  if (mqtt_reconfigured) {
    restart_mqtt(next_config.mqtt, *next);
  } else if (mqtt_) {
    mqtt_->use(*next);  // a changed device set is a Sparkplug rebirth
  }
  // The old gateway goes only after the handlers already queued for it (a housekeeping tick
  // that expired in this turn of the loop cannot be cancelled, and would find it freed).
  boost::asio::post(io_, [old = std::shared_ptr<Gateway>(std::move(gateway_))] {});
  gateway_ = std::move(next);
  config_ = std::move(next_config);
  restart_needed_ = std::move(restart);
  const std::vector<std::string> changed = diff_lines(diff);
  for (const auto& line : changed) log_->info("reload: {}", line);
  history_->record(EventKind::reload, "", 0,
                   changed.empty()
                       ? std::string("configuration reloaded: no device or bus changed")
                       : fmt::format("configuration reloaded: {}", fmt::join(changed, "; ")),
                   {{"result", "ok"},
                    {"kept", std::to_string(diff.devices_kept.size())},
                    {"restart_needed", fmt::format("{}", fmt::join(restart_needed_, ", "))}});
  log_->info("configuration reloaded: {} devices on {} buses; {} kept as they run{}{}{}",
             gateway_->devices().size(), config_.buses.size(), diff.devices_kept.size(),
             diff.devices_kept.empty() ? "" : ": ", fmt::join(diff.devices_kept, ", "),
             restart_needed_.empty()
                 ? std::string()
                 : fmt::format("; a restart is needed for {}", fmt::join(restart_needed_, ", ")));
  notifier_.ready(status_line());
}

// [mqtt] changed at a reload: the session ends as a clean one does (NDEATH, then DISCONNECT) and
// the new configuration's begins with its own births. The same edge node goes on from its bdSeq.
void Daemon::restart_mqtt(const MqttConfig& next, Gateway& gateway) {
  std::optional<std::uint8_t> previous;
  if (mqtt_) {
    if (config_.mqtt.group_id == next.group_id && config_.mqtt.edge_node_id == next.edge_node_id) {
      previous = mqtt_->status().bd_seq;
    }
    mqtt_->stop();
    // Freed after the handlers its client's closed socket and timers have already queued.
    boost::asio::post(io_, [old = std::shared_ptr<mqtt::Northbound>(std::move(mqtt_))] {});
  }
  if (next.enabled) {
    mqtt_ = std::make_unique<mqtt::Northbound>(io_, next, DRIVEGATE_VERSION, log_,
                                               options_.state_dir, previous);
    mqtt_->use(gateway);
    log_->info("[mqtt] applied: a new session with {} as {}/{}", next.brokers.at(0).url,
               next.group_id, next.edge_node_id);
  } else {
    log_->info("[mqtt] removed: the Sparkplug session ended");
  }
}

void Daemon::shutdown() {
  if (stopping_) return;
  stopping_ = true;
  notifier_.stopping();
  signals_.cancel();
  reload_timer_.cancel();
  pending_reload_.reset();  // never started: nothing of it runs
  gateway_->stop_drives(kStopLimit, Clock::now(), [this] {
    if (mqtt_) mqtt_->stop();
    if (http_) http_->close();
    server_->close();
    slaves_->close();
    gateway_->stop();
    status_timer_.cancel();
    watchdog_timer_.cancel();
    trend_timer_.cancel();
    io_.stop();
  });
}

std::string Daemon::status_line() const {
  return std::to_string(gateway_->devices_online()) + "/" +
         std::to_string(gateway_->devices().size()) + " devices online, " +
         std::to_string(gateway_->buses_open()) + "/" + std::to_string(config_.buses.size()) +
         " buses open, " + std::to_string(server_->client_count()) + " Modbus clients";
}

void Daemon::tick_status() {
  notifier_.status(status_line());
  status_timer_.expires_after(kStatusPeriod);
  status_timer_.async_wait([this](const boost::system::error_code& ec) {
    if (!ec && !stopping_) tick_status();
  });
}

void Daemon::tick_trends() {
  if (sampler_) sampler_->sample(*gateway_, EventLog::system_ms(), Clock::now());
  record_mqtt_state();
  history_->audit().flush(Clock::now());  // the summaries of folded writes now due
  trend_timer_.expires_after(kTrendPeriod);
  trend_timer_.async_wait([this](const boost::system::error_code& ec) {
    if (!ec && !stopping_) tick_trends();
  });
}

void Daemon::record_mqtt_state() {
  if (!mqtt_) return;
  const mqtt::NorthboundStatus s = mqtt_->status();
  std::string state = s.session + (s.connected ? "" : " (broker not connected)");
  if (state == mqtt_state_) return;
  history_->record(EventKind::mqtt, "", 0, "MQTT session: " + state,
                   {{"session", s.session}, {"connected", s.connected ? "true" : "false"}});
  mqtt_state_ = std::move(state);
}

// Pinged from the event loop itself: if the loop stalls, systemd's watchdog restarts us.
void Daemon::tick_watchdog() {
  const auto period = notifier_.watchdog_period();
  if (period.count() == 0) return;
  notifier_.watchdog();
  watchdog_timer_.expires_after(period);
  watchdog_timer_.async_wait([this](const boost::system::error_code& ec) {
    if (!ec) tick_watchdog();
  });
}

}  // namespace drivegate
