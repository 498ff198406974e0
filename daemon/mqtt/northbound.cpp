#include "mqtt/northbound.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <boost/asio/post.hpp>
#include <chrono>
#include <cmath>
#include <limits>
#include <utility>

#include "base/device_text.h"
#include "gateway/point_values.h"
#include "gateway/value_codec.h"
#include "mqtt/command_result.h"
#include "mqtt/sparkplug_codec.h"

namespace drivegate::mqtt {

namespace asio = boost::asio;
using sparkplug::DataType;
using sparkplug::MetricValue;

namespace {

constexpr Millis kFirstRetry{1'000};
constexpr Millis kLongestRetry{30'000};
// With several brokers: a primary host that says nothing on one (no retained STATE) for this long
// after the subscriptions may be online on another; the node looks there.
constexpr Millis kHostSilence{5'000};
// Sparkplug timestamps carry a value's age; a per-poll data age would be news at every poll.
constexpr std::string_view kNotPublished = "data_age_ms";

// The Sparkplug datatype of a point (docs/mqtt.md, "Metrics"). A 32-bit unsigned point goes out
// as Int64: the specification and Eclipse Tahu disagree on which field carries a UInt32.
DataType datatype_of(const PointSpec& spec) {
  if (is_bit_table(spec.table)) return DataType::boolean;
  switch (spec.type) {
    case PointType::string:
      return DataType::string;
    case PointType::f32:
      return DataType::float32;
    case PointType::f64:
      return DataType::float64;
    default:
      break;
  }
  if (spec.scale != 1.0 && spec.scale != 0.0) return DataType::float64;
  switch (spec.type) {
    case PointType::u16:
      return DataType::uint16;
    case PointType::i16:
      return DataType::int16;
    case PointType::u32:
      return DataType::int64;
    case PointType::i32:
      return DataType::int32;
    case PointType::u64:
      return DataType::uint64;
    case PointType::i64:
      return DataType::int64;
    default:
      return DataType::float64;
  }
}

MetricValue metric_value(DataType type, const Value& v) {
  if (std::holds_alternative<std::monostate>(v)) return {};
  switch (type) {
    case DataType::boolean:
      return MetricValue{as_double(v) != 0.0};
    case DataType::string:
      if (const auto* s = std::get_if<std::string>(&v)) {
        // A string point's text as the status JSON shows it: a protobuf string is UTF-8.
        std::string text;
        append_device_text(text, *s);
        return MetricValue{std::move(text)};
      }
      return {};
    case DataType::uint16:
      return MetricValue{static_cast<std::uint64_t>(as_double(v))};
    case DataType::uint64:
      // decode_value gives a u64 beyond an int64_t as a double.
      if (const auto* i = std::get_if<std::int64_t>(&v)) {
        return MetricValue{static_cast<std::uint64_t>(*i)};
      }
      return MetricValue{static_cast<std::uint64_t>(std::min(as_double(v), 1.8446744073709550e19))};
    case DataType::int16:
    case DataType::int32:
    case DataType::int64:
      if (const auto* i = std::get_if<std::int64_t>(&v)) return MetricValue{*i};
      return MetricValue{static_cast<std::int64_t>(as_double(v))};
    default:
      return MetricValue{as_double(v)};
  }
}

Value drive_value(const MetricValue& v) {
  if (const auto* b = std::get_if<bool>(&v)) return std::int64_t{*b ? 1 : 0};
  if (const auto* i = std::get_if<std::int64_t>(&v)) return *i;
  if (const auto* u = std::get_if<std::uint64_t>(&v)) {
    if (*u <= static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max())) {
      return static_cast<std::int64_t>(*u);
    }
    return static_cast<double>(*u);
  }
  if (const auto* d = std::get_if<double>(&v)) return *d;
  return {};
}

// A scaled point's value on its own grid: 12 steps of 0.1 is 1.2, not 1.2000000000000002.
Value in_steps(const PointSpec& spec, Value v) {
  const auto* d = std::get_if<double>(&v);
  if (d == nullptr || spec.scale == 0.0 || spec.scale >= 1.0) return v;
  const double per_unit = std::round(1.0 / spec.scale);
  if (std::fabs(per_unit * spec.scale - 1.0) > 1e-9) return v;  // not 1/n: leave it
  return std::round(*d * per_unit) / per_unit;
}

sparkplug::Property property(std::string key, MetricValue value) {
  DataType type = DataType::string;
  if (std::holds_alternative<double>(value)) type = DataType::float64;
  if (std::holds_alternative<bool>(value)) type = DataType::boolean;
  return {std::move(key), type, std::move(value)};
}

// [mqtt] store_forward's store, in the state directory; none without one (said once), or when
// it cannot be opened (said why). The stores of other edge node ids there are named in the log.
std::unique_ptr<StoreForward> make_store(const MqttConfig& config,
                                         const std::filesystem::path& state_dir,
                                         const std::shared_ptr<spdlog::logger>& log) {
  if (state_dir.empty()) {
    if (!config.store_forward) return nullptr;
    log->info(
        "MQTT: changes while the broker is away are not kept: no state directory "
        "(drivegated --state-dir, or StateDirectory= in the unit)");
    return nullptr;
  }
  const auto own = edge_node_state_path(state_dir, config.group_id, config.edge_node_id, ".store");
  for (const auto& other : other_edge_node_state(own)) {
    log->warn(
        "MQTT: {} holds changes kept under another group_id or edge_node_id; nothing sends them "
        "now: remove it once they are not needed",
        other.string());
  }
  if (!config.store_forward) return nullptr;
  SpoolLimits limits;
  limits.max_bytes = config.store_max_bytes;
  limits.max_age = config.store_max_age;
  auto store = std::make_unique<StoreForward>(own, limits, config.replay_per_s, log);
  if (!store->open()) return nullptr;
  return store;
}

// A DCMD the edge node refused, as the audit trail's result: the one a Modbus client would get
// for the same mistake (docs/audit.md, RESULT).
Outcome outcome_of(sparkplug::Refusal r) {
  using sparkplug::Refusal;
  switch (r) {
    case Refusal::retained:
      return Outcome::refused;
    case Refusal::unknown_device:
      return Outcome::no_such_device;
    case Refusal::commands_off:
      return Outcome::denied;  // as a read-only session's write
    case Refusal::unknown_metric:
      return Outcome::no_such_point;
    case Refusal::malformed:
    case Refusal::wrong_type:
      return Outcome::invalid_value;
    case Refusal::not_born:
      return Outcome::refused;
  }
  return Outcome::invalid_value;
}

}  // namespace

BrokerOptions broker_options(const MqttConfig& config, std::size_t index) {
  const MqttBroker& b = config.brokers.at(index);
  return {b.host,
          b.port,
          b.tls,
          b.ca.string(),
          b.cert.string(),
          b.key.string(),
          config.client_id,
          config.username,
          config.password,
          config.keepalive,
          std::chrono::milliseconds(10'000)};
}

Northbound::Northbound(asio::io_context& io, const MqttConfig& config, std::string version,
                       std::shared_ptr<spdlog::logger> log, const std::filesystem::path& state_dir,
                       std::optional<std::uint8_t> previous_bd_seq)
    : io_(io),
      config_(config),
      log_(log),
      bd_seq_file_(state_dir, config.group_id, config.edge_node_id),
      store_(make_store(config, state_dir, log)),
      edge_(
          sparkplug::EdgeNodeOptions{.group = config.group_id,
                                     .edge_node = config.edge_node_id,
                                     .primary_host = config.primary_host_id,
                                     .host_state = config.primary_host_state == MqttHostState::v2_2
                                                       ? sparkplug::HostStateForm::v2_2
                                                       : sparkplug::HostStateForm::v3_0,
                                     .min_interval = config.min_interval,
                                     .counter_interval = config.counter_interval,
                                     .commands = config.commands,
                                     .version = std::move(version),
                                     .last_bd_seq = last_bd_seq(previous_bd_seq),
                                     .store_forward = store_ != nullptr}),
      client_(
          io, broker_options(config, 0),
          MosquittoClient::Handlers{[this] { connected(); }, [this](std::string why) { lost(why); },
                                    [this](std::string_view t, std::string_view p, bool retained) {
                                      message(t, p, retained);
                                    },
                                    [this](std::uint64_t up_to) { delivered(up_to); }},
          log),
      retry_timer_(io),
      tick_timer_(io),
      pace_timer_(io),
      host_timer_(io) {
  status_.broker = config.brokers.at(0).url;
  status_.brokers = config.brokers.size();
  if (store_) pace();
}

Northbound::~Northbound() {
  alive_.reset();
  for (const Watched& w : watched_) w.device->watch({});
}

std::optional<std::uint8_t> Northbound::last_bd_seq(std::optional<std::uint8_t> previous) const {
  if (previous) return previous;
  if (!bd_seq_file_.enabled()) {
    log_->info(
        "MQTT: the bdSeq starts at 0: no state directory to keep it in across restarts "
        "(drivegated --state-dir, or StateDirectory= in the unit)");
    return std::nullopt;
  }
  std::string error;
  const auto saved = bd_seq_file_.load(error);
  if (!error.empty()) {
    log_->warn("MQTT: {}; the bdSeq starts at 0", error);
  } else if (saved) {
    log_->info("MQTT: the last session's bdSeq was {} ({})", *saved, bd_seq_file_.path().string());
  }
  return saved;
}

void Northbound::use(Gateway& gateway) {
  ++generation_;
  gateway_ = &gateway;
  std::vector<sparkplug::DeviceDef> defs;
  watched_.clear();
  const std::weak_ptr<bool> token = alive_;
  for (const auto& d : gateway.devices()) {
    watched_.push_back({d.get(), {}, {}, {}, std::nullopt, 0});
    defs.push_back(define(*d, watched_.back()));
    const std::size_t index = watched_.size() - 1;
    d->watch([this, token, index, generation = generation_] {
      if (!token.expired()) changed(index, generation);
    });
  }
  for (const auto& deadband : config_.deadband) {
    const std::string& name = deadband.first;  // clang 14 cannot capture a structured binding
    const bool known = std::any_of(defs.begin(), defs.end(), [&](const auto& def) {
      return std::any_of(def.metrics.begin(), def.metrics.end(),
                         [&](const auto& m) { return m.name == name; });
    });
    if (!known) log_->warn("[mqtt] deadband: no device has a point named '{}'", name);
  }
  dirty_.assign(watched_.size(), true);
  if (edge_.set_devices(std::move(defs), now(), *this) && started_) {
    log_->info("MQTT: devices changed: rebirth");
  }
  flush();
  if (!started_) {
    started_ = true;
    connect();
  }
}

void Northbound::stop() {
  stopping_ = true;
  retry_timer_.cancel();
  tick_timer_.cancel();
  pace_timer_.cancel();
  host_timer_.cancel();
  for (const Watched& w : watched_) w.device->watch({});
  watched_.clear();
  gateway_ = nullptr;
  dirty_.clear();
  if (client_.connected()) {
    // A clean DISCONNECT makes the broker drop the will: the NDEATH goes out by hand (spec 5.6).
    client_.publish(edge_.will_topic(), sparkplug::encode(edge_.node_death(now())), 1, false);
    ++status_.messages;
  }
  client_.disconnect();
  session_ended();
  if (store_) store_->sync();
}

void Northbound::session_ended() {
  edge_.connection_lost();
  // What the broker did not confirm is kept for the next session (store_forward.h).
  if (store_) store_->lost(now().unix_ms);
}

NorthboundStatus Northbound::status() const {
  NorthboundStatus s = status_;
  s.session = std::string(sparkplug::to_string(edge_.state()));
  s.connected = client_.connected();
  s.bd_seq = edge_.bd_seq();
  s.births = edge_.births();
  s.commands_retained = edge_.retained_ignored();
  s.rebirths_coalesced = edge_.rebirths_coalesced();
  if (store_) s.store = store_->stats(edge_);
  return s;
}

void Northbound::connect() {
  if (stopping_) return;
  // Here, never in lost(): that runs inside libmosquitto's callback, whose client it would reset.
  if (client_broker_ != broker_) {
    client_.use_broker(broker_options(config_, broker_));
    client_broker_ = broker_;
  }
  const auto will = edge_.begin_connect(now());
  // Kept before the will can reach the broker: whatever happens next, the next start goes on
  // from this one. A state directory that cannot be written does not stop the session.
  if (const auto ec = bd_seq_file_.save(edge_.bd_seq())) {
    if (!bd_seq_save_failed_) {
      log_->warn("MQTT: cannot keep the bdSeq in {}: {}; a restart may reuse it",
                 bd_seq_file_.path().string(), ec.message());
    }
    bd_seq_save_failed_ = true;
  } else {
    bd_seq_save_failed_ = false;
  }
  client_.connect(edge_.will_topic(), sparkplug::encode(will));
}

void Northbound::connected() {
  ++status_.connects;
  session_up_ = true;
  status_.last_error.clear();
  log_->info("MQTT: connected to {} as {} (bdSeq {}){}", broker_url(), config_.client_id,
             edge_.bd_seq(),
             config_.primary_host_id.empty()
                 ? ""
                 : fmt::format(", waiting for primary host '{}'", config_.primary_host_id));
  backoff_ = Millis{0};
  for (const auto& topic : edge_.subscriptions()) client_.subscribe(topic, 1);
  // Fresh values for the births.
  std::fill(dirty_.begin(), dirty_.end(), true);
  flush();
  edge_.connected(now(), *this, broker_);
  schedule_tick();
  if (edge_.state() == sparkplug::SessionState::waiting_for_host && config_.brokers.size() > 1) {
    // A host that says nothing here (no retained STATE) may be online on another broker.
    host_timer_.expires_after(kHostSilence);
    host_timer_.async_wait([this, session = status_.connects](const boost::system::error_code& ec) {
      if (ec || stopping_ || session != status_.connects || !client_.connected() ||
          edge_.state() != sparkplug::SessionState::waiting_for_host) {
        return;
      }
      log_->warn("MQTT: no STATE from primary host '{}' on {} within {} s: trying the next broker",
                 config_.primary_host_id, broker_url(), kHostSilence.count() / 1000);
      walk_on();
    });
  }
}

void Northbound::lost(const std::string& why) {
  session_ended();
  if (stopping_) return;
  ++status_.losses;
  if (std::exchange(session_up_, false)) ++status_.sessions_lost;
  const bool first = status_.last_error.empty();
  status_.last_error = why;
  backoff_ = backoff_.count() == 0 ? kFirstRetry : std::min(backoff_ * 2, kLongestRetry);
  // One warning per outage; the retries after it only at debug level.
  const std::string failed = broker_url();
  const bool walk = next_broker();
  if (first) {
    log_->warn("MQTT: {}: {}; {} (Modbus is not affected)", failed, why,
               walk ? fmt::format("trying {} next", broker_url())
                    : fmt::format("retrying every {} s at most", kLongestRetry.count() / 1000));
  } else {
    log_->debug("MQTT: {}: {}; next attempt{} in {} ms at most", failed, why,
                walk ? " on " + broker_url() : std::string(), backoff_.count());
  }
  connect_after(backoff_);
}

void Northbound::connect_after(Millis delay) {
  // Gateways that lost their broker together would retry together, every one at the same
  // instants of the back-off (1 s, 3 s, 7 s...), and a fleet's reconnects and births would hit
  // the broker in bursts. Each waits a random part of the delay instead, from half of it to all
  // of it ("equal jitter"): never later than the back-off says, spread over its second half.
  std::uniform_int_distribution<Millis::rep> spread(delay.count() / 2, delay.count());
  retry_timer_.expires_after(Millis{spread(random_)});
  retry_timer_.async_wait([this](const boost::system::error_code& ec) {
    if (!ec) connect();
  });
}

void Northbound::message(std::string_view topic, std::string_view payload, bool retained) {
  edge_.message(topic, payload, now(), *this, retained);
  if (edge_.state() == sparkplug::SessionState::online) walk_backoff_ = Millis{0};
  schedule_tick();
}

void Northbound::changed(std::size_t index, std::uint64_t generation) {
  if (generation != generation_ || index >= dirty_.size()) return;
  dirty_[index] = true;
  if (flush_posted_) return;
  flush_posted_ = true;
  // After the engine's turn: a reply that changed several values is one sample, not several.
  asio::post(io_, [this, token = std::weak_ptr<bool>(alive_), generation] {
    if (token.expired()) return;
    flush_posted_ = false;
    if (generation == generation_) flush();
  });
}

void Northbound::flush() {
  if (!store_ && edge_.state() == sparkplug::SessionState::offline && !client_.connected()) {
    // Nobody to tell and nothing kept: the next session's births sample every device afresh.
    return;
  }
  const auto t = now();
  for (std::size_t i = 0; i < watched_.size(); ++i) {
    if (!dirty_[i]) continue;
    dirty_[i] = false;
    Watched& w = watched_[i];
    const Device& d = *w.device;
    const bool alive = d.line().health.ever_good() && !d.comm_lost();
    // When the drive's state last arrived, on the payload's clock: a write's echo never counts.
    // Worked out once per reply (two clocks read a moment apart would put the same reply a
    // millisecond either way), and never before the last one's.
    if (const auto at = d.line().health.last_data(); at && at != w.data_at) {
      const auto age = std::chrono::duration_cast<Millis>(t.mono - *at).count();
      const std::uint64_t ms = t.unix_ms - static_cast<std::uint64_t>(std::clamp<std::int64_t>(
                                               age, 0, static_cast<std::int64_t>(t.unix_ms)));
      w.data_at = at;
      w.data_ms = std::max(w.data_ms, ms);
    }
    edge_.sample(i, alive, sample(w), w.data_ms, t, *this);
  }
  schedule_tick();
}

void Northbound::schedule_tick() {
  const auto at = edge_.wake_at();
  if (!at) return;
  tick_timer_.expires_at(*at);
  tick_timer_.async_wait([this](const boost::system::error_code& ec) {
    if (ec) return;
    edge_.tick(now(), *this);
    schedule_tick();
  });
}

sparkplug::Now Northbound::now() const {
  const auto unix = std::chrono::duration_cast<std::chrono::milliseconds>(
      std::chrono::system_clock::now().time_since_epoch());
  return {Clock::now(), static_cast<std::uint64_t>(unix.count())};
}

sparkplug::DeviceDef Northbound::define(const Device& device, Watched& watched) const {
  sparkplug::DeviceDef def{device.name(), {}};
  for (const MappedPoint& p : device.map().points()) {
    if (p.spec.name == kNotPublished) {
      watched.metric_of.push_back(-1);
      continue;
    }
    sparkplug::MetricDef m;
    m.name = p.spec.name;
    m.type = datatype_of(p.spec);
    const bool writable = p.spec.access() == Access::read_write;
    if (!p.spec.unit.empty()) m.properties.push_back(property("engUnit", p.spec.unit));
    if (writable && (p.spec.min != 0.0 || p.spec.max != 0.0)) {
      m.properties.push_back(property("engLow", p.spec.min));
      m.properties.push_back(property("engHigh", p.spec.max));
    }
    // What a DCMD could actually write: commands on, and within the session's access level.
    const bool commandable = writable && config_.commands && required_level(p) <= config_.access;
    m.properties.push_back(property("readOnly", !commandable));
    for (const auto& [name, amount] : config_.deadband) {
      if (name == m.name) m.deadband = amount;
    }
    m.counter = p.row() != nullptr && p.row()->counter;
    // Whether the command's session may write it is the device's to say, as for Modbus.
    m.writable = writable;
    watched.metric_of.push_back(static_cast<std::int32_t>(def.metrics.size()));
    def.metrics.push_back(std::move(m));
    watched.points.push_back(&p);
  }
  return def;
}

std::vector<MetricValue> Northbound::sample(Watched& watched) const {
  Device& device = *watched.device;
  point_values(device, Clock::now(), watched.scratch);
  // point_values() gives the map's points in its order, leaving out any it cannot read; the
  // metrics are the map's points but data_age_ms, in the same order.
  std::vector<MetricValue> values(watched.points.size());
  const MappedPoint* first = device.map().points().data();
  for (const auto& [point, value] : watched.scratch) {
    const auto at = watched.metric_of[static_cast<std::size_t>(point - first)];
    if (at < 0) continue;
    const PointSpec& spec = point->spec;
    values[static_cast<std::size_t>(at)] = metric_value(datatype_of(spec), in_steps(spec, value));
  }
  return values;
}

bool Northbound::publish(const std::string& topic, const sparkplug::Payload& payload) {
  const bool taken = client_.publish(topic, sparkplug::encode(payload), 0, false);
  if (!taken) return false;
  ++status_.messages;
  if (store_) store_->sent(client_.published(), topic, payload);
  return true;
}

void Northbound::store(std::string_view device, const sparkplug::Payload& historical) {
  if (store_) store_->keep(device, historical, now().unix_ms);
}

void Northbound::delivered(std::uint64_t up_to) {
  if (!store_) return;
  const bool was_full = store_->window_full();
  store_->delivered(up_to);
  // The replay waited for this: it goes on at once, within this period's budget.
  if (was_full && !replay_posted_) {
    replay_posted_ = true;
    asio::post(io_, [this, token = std::weak_ptr<bool>(alive_)] {
      if (!token.expired()) replay_step();
    });
  }
}

void Northbound::pace() {
  pace_timer_.expires_after(StoreForward::kReplayPeriod);
  pace_timer_.async_wait([this](const boost::system::error_code& ec) {
    if (ec || stopping_) return;
    replay_budget_ = store_->batch();  // this period's; what the last did not use is gone
    if (!replay_posted_) replay_step();
    if (++paces_ % 10 == 0) store_->sync();
    pace();
  });
}

// One record per turn of the event loop: a Modbus request, a poll's reply or a live change waits
// behind one record's work at most, whatever replay_per_s says.
void Northbound::replay_step() {
  replay_posted_ = false;
  // A broker slower than the replay: wait for what is queued to go before adding more.
  if (stopping_ || replay_budget_ == 0 || edge_.state() != sparkplug::SessionState::online ||
      !store_->waiting() || client_.busy()) {
    return;
  }
  --replay_budget_;
  // Nothing could go (its device's DBIRTH awaited, the client refused): the next period retries.
  const unsigned sent = store_->replay(edge_, *this, now(), 1);
  if (store_->window_full()) client_.confirm_now();  // the replay goes on once it is confirmed
  if (sent == 0) return;
  replay_posted_ = true;
  asio::post(io_, [this, token = std::weak_ptr<bool>(alive_)] {
    if (!token.expired()) replay_step();
  });
}

void Northbound::drop_session() {
  // The NDEATH is out: what the broker did not confirm goes back to the store now, before any
  // change kept from here on.
  if (store_) store_->lost(now().unix_ms);
  log_->warn(
      "MQTT: primary host '{}' is offline: NDEATH published, session ended; "
      "reconnecting to wait for it",
      config_.primary_host_id);
  backoff_ = kFirstRetry;
  leave_broker(backoff_);
}

void Northbound::host_offline_before_births() {
  if (config_.brokers.size() < 2) return;  // nowhere else to look: wait here for the host
  log_->warn("MQTT: primary host '{}' is offline on {}: trying the next broker",
             config_.primary_host_id, broker_url());
  walk_on();
}

void Northbound::walk_on() {
  // Growing while no broker has the host online, so a plant whose host is down is not
  // reconnected to every second: 1 s, 2 s, 4 s... 30 s, back to 1 s once born somewhere.
  walk_backoff_ =
      walk_backoff_.count() == 0 ? kFirstRetry : std::min(walk_backoff_ * 2, kLongestRetry);
  leave_broker(walk_backoff_);
}

void Northbound::leave_broker(Millis delay) {
  // Out of libmosquitto's callback first: inside it, packets are only queued, and an NDEATH just
  // published must reach the broker before the DISCONNECT that makes it drop the will.
  asio::post(io_, [this, token = std::weak_ptr<bool>(alive_), delay] {
    // Once: a second STATE in the same turn, or a lost session, finds it already ended.
    if (token.expired() || stopping_ || !client_.connected()) return;
    client_.disconnect();
    session_up_ = false;  // left, not lost
    session_ended();
    // Spec 5.x (multiple MQTT servers): the host may be online on another server.
    if (next_broker()) log_->info("MQTT: trying {} next", broker_url());
    connect_after(delay);
  });
}

bool Northbound::next_broker() {
  if (config_.brokers.size() < 2) return false;
  broker_ = (broker_ + 1) % config_.brokers.size();  // the client moves at the next connect()
  status_.broker = broker_url();
  status_.broker_index = broker_;
  ++status_.broker_switches;
  return true;
}

const std::string& Northbound::broker_url() const {
  return config_.brokers.at(broker_).url;
}

void Northbound::write(std::size_t device, std::vector<sparkplug::PointCommand> points) {
  if (device >= watched_.size()) return;
  const Watched& w = watched_[device];
  std::vector<Device::PointWrite> writes;
  std::string names;
  for (const auto& pc : points) {
    const MappedPoint* p = w.points.at(pc.index);
    writes.push_back({p, drive_value(pc.value)});
    names += (names.empty() ? "" : ",") + p->spec.name;
  }
  ++status_.commands;
  Session session{config_.access, WordOrder::big, config_.feed_failsafe};
  session.source = source();
  const std::string name = w.device->name();
  log_->info("MQTT: DCMD {} {}", name, names);
  auto report = [this, token = std::weak_ptr<bool>(alive_), name, names](Outcome outcome) {
    if (token.expired()) return;
    const auto& defs = edge_.devices();
    const auto it = std::find_if(defs.begin(), defs.end(),
                                 [&](const sparkplug::DeviceDef& d) { return d.name == name; });
    const std::string result(command_result(outcome));
    if (outcome != Outcome::ok) {
      notice(sparkplug::Notice::command, fmt::format("DCMD {} {}: {}", name, names, result));
    }
    if (it != defs.end()) {
      edge_.command_done(static_cast<std::size_t>(it - defs.begin()), names, result, now(), *this);
    }
  };
  const Outcome at_once = w.device->write_points(session, writes, report, Clock::now());
  if (at_once != Outcome::ok) report(at_once);  // refused before anything was applied
}

// A DCMD does not say who published it: the audit trail names the broker, our session's client
// id, and the primary host the commands are expected from while it is online (the node is born);
// otherwise no host is named, and the refusal says why.
Source Northbound::source() const {
  Source s;
  s.kind = SourceKind::mqtt;
  s.listener = broker_url();
  const bool host_online = edge_.state() == sparkplug::SessionState::online;
  s.client = config_.primary_host_id.empty() || !host_online
                 ? config_.client_id
                 : config_.client_id + " (primary host " + config_.primary_host_id + ")";
  return s;
}

void Northbound::refused(sparkplug::RefusedCommand c) {
  using sparkplug::Refusal;
  notice(c.refusal == Refusal::retained ? sparkplug::Notice::retained : sparkplug::Notice::command,
         fmt::format("DCMD for {} refused: {}", c.device, c.why));
  if (gateway_ == nullptr) return;
  const Device* device = gateway_->find(c.device);
  if (device == nullptr && c.refusal == Refusal::unknown_device) {
    c.why = "no device named '" + c.device + "'";
  } else if (device == nullptr) {  // retained, for a device this gateway does not have
    c.why += " (no device named '" + c.device + "')";
  }
  gateway_->refused_write(source(), device, std::move(c.points), outcome_of(c.refusal),
                          std::move(c.why));
}

// Anyone who can publish to the broker can cause these: a burst, then one a second per kind.
void Northbound::notice(sparkplug::Notice kind, std::string message) {
  if (const auto held = notice_log_.at(static_cast<std::size_t>(kind)).admit(Clock::now())) {
    log_->warn("MQTT: {}{}", message, net::held_note(*held));
  }
}

}  // namespace drivegate::mqtt
