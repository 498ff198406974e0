#include "mqtt/edge_node.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>

#include "mqtt/sparkplug_codec.h"

namespace drivegate::sparkplug {

namespace {

constexpr std::array<std::string_view, 3> kSessionNames = {"offline", "waiting_for_host", "online"};

Metric bd_seq_metric(std::uint8_t bd_seq) {
  return {std::string(kBdSeq), DataType::uint64, MetricValue{std::uint64_t{bd_seq}}, {}, {}, false};
}

Metric string_metric(std::string_view name, std::string value) {
  return {std::string(name), DataType::string, MetricValue{std::move(value)}, {}, {}, false};
}

// Whether `now` differs from `before` enough to be reported under `def`.
bool moved(const MetricDef& def, const MetricValue& before, const MetricValue& now) {
  if (before == now) return false;
  if (def.deadband <= 0.0) return true;
  const auto a = number_of(before);
  const auto b = number_of(now);
  if (!a || !b) return true;  // from or to null: always news
  return std::fabs(*b - *a) >= def.deadband;
}

// What a refused DCMD asked, for the audit trail: its metrics' names and values as they came,
// printable and bounded (anyone on the broker writes them, and the journal and the history get
// them): its device name and the reason, which may quote a metric's name, likewise.
constexpr std::size_t kAskedMax = 256;
constexpr std::size_t kNameMax = 64;
constexpr std::size_t kDecodeMax = 64 * 1024;  // larger: said by its size, not decoded for this

void append_printable(std::string& out, std::string_view text) {
  for (const char c : text) out += (c >= 0x20 && c < 0x7F) ? c : '?';
}

std::string printable(std::string_view text, std::size_t max) {
  std::string out;
  append_printable(out, text.substr(0, max));
  return text.size() > max ? out + "..." : out;
}

std::string value_text(const MetricValue& v) {
  if (const auto* b = std::get_if<bool>(&v)) return *b ? "true" : "false";
  if (const auto* i = std::get_if<std::int64_t>(&v)) return std::to_string(*i);
  if (const auto* u = std::get_if<std::uint64_t>(&v)) return std::to_string(*u);
  if (const auto* d = std::get_if<double>(&v)) {
    std::array<char, 32> buf{};
    const auto r = std::to_chars(buf.data(), buf.data() + buf.size(), *d);
    return {buf.data(), r.ptr};
  }
  if (const auto* text = std::get_if<std::string>(&v)) return "\"" + printable(*text, 32) + "\"";
  return "null";
}

std::string asked(const Payload& p) {
  std::string out;
  for (const Metric& m : p.metrics) {
    if (out.size() >= kAskedMax) return out + " ...";
    if (!out.empty()) out += ' ';
    if (m.name.empty()) {
      out += "<alias>";
    } else {
      append_printable(out, std::string_view(m.name).substr(0, kNameMax));
    }
    out += "=" + value_text(m.value);
  }
  return out.empty() ? "<no metrics>" : out;
}

std::string asked(std::string_view payload) {
  std::string why;
  const auto p = payload.size() <= kDecodeMax ? decode(payload, why) : std::nullopt;
  return p ? asked(*p) : "<" + std::to_string(payload.size()) + " bytes>";
}

RefusedCommand make_refusal(std::string_view device, std::string points, Refusal kind,
                            std::string_view why) {
  return {printable(device, kNameMax), std::move(points), kind, printable(why, kAskedMax)};
}

}  // namespace

std::string_view to_string(SessionState s) {
  return kSessionNames.at(static_cast<std::size_t>(s));
}

EdgeNode::EdgeNode(EdgeNodeOptions options)
    : options_(std::move(options)), bd_seq_(options_.last_bd_seq.value_or(255)) {}

Payload EdgeNode::begin_connect(const Now& now) {
  ++bd_seq_;  // wraps 255 -> 0 (spec 6.4.19)
  return node_death(now);
}

Payload EdgeNode::node_death(const Now& now) const {
  Payload p;
  p.timestamp = now.unix_ms;
  p.metrics.push_back(bd_seq_metric(bd_seq_));
  return p;  // no seq in an NDEATH (spec 6.4.1)
}

std::string EdgeNode::will_topic() const {
  return topic(options_.group, MessageType::ndeath, options_.edge_node);
}

std::vector<std::string> EdgeNode::subscriptions() const {
  std::vector<std::string> s = {topic(options_.group, MessageType::ncmd, options_.edge_node),
                                topic(options_.group, MessageType::dcmd, options_.edge_node, "+")};
  if (!options_.primary_host.empty()) {
    s.push_back(state_topic(options_.primary_host, options_.host_state));
  }
  return s;
}

void EdgeNode::connected(const Now& now, Sink& sink, std::size_t broker) {
  broker_ = broker;
  if (host_online_.size() <= broker) host_online_.resize(broker + 1, 0);
  host_said_offline_ = false;
  if (options_.primary_host.empty()) {
    state_ = SessionState::online;
    online_since_ = now.mono;
    rebirth(now, sink);
  } else {
    state_ = SessionState::waiting_for_host;  // the retained STATE arrives with the subscription
  }
}

void EdgeNode::connection_lost() {
  state_ = SessionState::offline;
  rebirth_due_.reset();
  for (DeviceState& d : devices_) {
    d.born = false;
    d.due.reset();
  }
}

void EdgeNode::message(std::string_view t, std::string_view payload, const Now& now, Sink& sink,
                       bool retained) {
  if (!options_.primary_host.empty() &&
      t == state_topic(options_.primary_host, options_.host_state)) {
    host_state(payload, now, sink);  // STATE is retained by design (spec 4.2.1)
    return;
  }
  const auto parsed = parse_topic(t);
  if (!parsed || parsed->group != options_.group || parsed->edge_node != options_.edge_node) {
    return;  // not ours (a wildcard subscription elsewhere would bring such)
  }
  const bool is_command = parsed->type == MessageType::dcmd || parsed->type == MessageType::ncmd;
  if (!is_command) return;
  // How a retained command is cleared (an empty retained publish on its topic): the broker hands
  // the empty message to its subscribers too. It asks nothing.
  if (payload.empty()) {
    sink.notice(Notice::command, "empty " + std::string(to_string(parsed->type)) + " on " +
                                     printable(t, kAskedMax) +
                                     " ignored (a retained command cleared)");
    return;
  }
  // Spec 6.4 (NCMD, DCMD): "MUST be published with the MQTT retain flag set to false". One that
  // was kept by the broker is an old command replayed at this subscription, not a host asking
  // now: a retained run_forward would start a motor a PLC stopped at every reconnect.
  if (retained) {
    ++retained_ignored_;
    const std::string why =
        "retained by the broker: a command is carried out only when it is live (clear it with an "
        "empty retained message)";
    if (parsed->type == MessageType::dcmd) {
      sink.refused(make_refusal(parsed->device, asked(payload), Refusal::retained, why));
    } else {
      sink.notice(Notice::retained, "NCMD on " + std::string(t) + " ignored: " + why);
    }
    return;
  }
  if (parsed->type == MessageType::dcmd) {
    command(parsed->device, payload, now, sink);
    return;
  }
  std::string why;
  const auto p = decode(payload, why);
  if (!p) {
    sink.notice(Notice::command, "NCMD ignored: " + why);
    return;
  }
  if (const std::string refused = not_born(devices_.size()); !refused.empty()) {
    sink.notice(Notice::command, "NCMD ignored: " + refused);
    return;
  }
  for (const Metric& m : p->metrics) {
    if (m.name == kRebirth && m.value == MetricValue{true}) {
      rebirth_requested(now, sink);
    } else {
      sink.notice(Notice::command, "NCMD metric '" + m.name + "' ignored: only " +
                                       std::string(kRebirth) + " = true is understood");
    }
  }
}

// A host asked for a rebirth: at once unless one went out less than kRebirthInterval ago; then
// once that has passed, for every request made meanwhile.
void EdgeNode::rebirth_requested(const Now& now, Sink& sink) {
  if (rebirth_due_) {
    ++rebirths_coalesced_;
    return;
  }
  if (!last_rebirth_ || now.mono >= *last_rebirth_ + kRebirthInterval) {
    last_rebirth_ = now.mono;
    rebirth(now, sink);
    return;
  }
  ++rebirths_coalesced_;
  rebirth_due_ = *last_rebirth_ + kRebirthInterval;
  sink.notice(Notice::rebirth, "rebirth requested again within " +
                                   std::to_string(kRebirthInterval.count()) +
                                   " ms: one rebirth answers every request until then");
}

void EdgeNode::host_state(std::string_view payload, const Now& now, Sink& sink) {
  const auto s = parse_host_state(payload, options_.host_state);
  if (!s) {
    sink.notice(
        Notice::host_state,
        "STATE of primary host '" + options_.primary_host + "' ignored: not " +
            (options_.host_state == HostStateForm::v2_2 ? "ONLINE or OFFLINE (Sparkplug 2.2)"
                                                        : "{\"online\": bool, \"timestamp\": ms}"));
    return;
  }
  // A timestamp from the future would make every genuine STATE after it look stale (below).
  if (s->timestamp > now.unix_ms + static_cast<std::uint64_t>(kStateClockTolerance.count())) {
    sink.notice(Notice::host_state, "STATE of primary host '" + options_.primary_host +
                                        "' ignored: its timestamp " + std::to_string(s->timestamp) +
                                        " is more than " +
                                        std::to_string(kStateClockTolerance.count() / 1000) +
                                        " s ahead of this gateway's clock (" +
                                        std::to_string(now.unix_ms) + "; check both clocks)");
    return;
  }
  // Spec 5.13: a STATE older than the newest one seen is stale (a late copy). Which is newest is
  // this broker's own sequence: a host online on two brokers stamps each connection there with
  // its own time. Only an ONLINE sets the mark: a host's death certificate carries the timestamp
  // of its birth (its ONLINE), so an offline older than the ONLINE believed is an earlier
  // session's, while an offline (forged, or from a clock ahead) must never make the host's next
  // genuine ONLINE look stale.
  if (host_online_.size() <= broker_) host_online_.resize(broker_ + 1, 0);
  std::uint64_t& mark = host_online_[broker_];
  if (s->timestamp < mark) return;
  if (s->online) mark = s->timestamp;
  host_said_offline_ = !s->online;
  if (s->online && state_ == SessionState::waiting_for_host) {
    state_ = SessionState::online;
    online_since_ = now.mono;
    rebirth(now, sink);
  } else if (!s->online && state_ == SessionState::online) {
    sink.publish(will_topic(), node_death(now));
    connection_lost();
    sink.drop_session();
  } else if (!s->online && state_ == SessionState::waiting_for_host) {
    sink.host_offline_before_births();
  }
}

bool EdgeNode::set_devices(std::vector<DeviceDef> devices, const Now& now, Sink& sink) {
  if (devices == defs_) return false;
  if (state_ == SessionState::online) {
    for (std::size_t i = 0; i < defs_.size(); ++i) {
      const bool kept = std::any_of(devices.begin(), devices.end(),
                                    [&](const DeviceDef& d) { return d.name == defs_[i].name; });
      if (!kept && devices_[i].born) death(i, now, sink);
    }
  }
  // A device defined as before goes on as it was: what was reported (or kept) of it is not news
  // again, nor kept twice.
  std::vector<DeviceState> next(devices.size());
  for (std::size_t i = 0; i < devices.size(); ++i) {
    const auto same = std::find(defs_.begin(), defs_.end(), devices[i]);
    if (same != defs_.end())
      next[i] = std::move(devices_[static_cast<std::size_t>(same - defs_.begin())]);
  }
  defs_ = std::move(devices);
  devices_ = std::move(next);
  if (state_ == SessionState::online) rebirth(now, sink);
  return true;
}

void EdgeNode::sample(std::size_t device, bool alive, std::vector<MetricValue> values,
                      std::uint64_t data_ms, const Now& now, Sink& sink) {
  if (device >= devices_.size() || values.size() != defs_[device].metrics.size()) return;
  DeviceState& d = devices_[device];
  d.alive = alive;
  // A value that changed with no new reply from the drive since the last sample (a setpoint
  // written while stopped) is as of now: the last reply's time is from before it held.
  d.changed_ms.resize(values.size(), 0);
  if (d.latest.size() == values.size() && data_ms <= d.data_ms) {
    for (std::size_t j = 0; j < values.size(); ++j) {
      if (values[j] != d.latest[j]) d.changed_ms[j] = now.unix_ms;
    }
  }
  d.latest = std::move(values);
  d.data_ms = data_ms;
  if (state_ != SessionState::online) {
    keep(device, now, sink);
    return;
  }
  if (!alive) {
    if (d.born) death(device, now, sink);
    return;
  }
  if (!d.born) {
    birth(device, now, sink);
    return;
  }
  report_or_hold(device, now, sink);
}

// What changed goes now (report()), or once min_interval has passed since the last (tick()).
void EdgeNode::report_or_hold(std::size_t device, const Now& now, Sink& sink) {
  DeviceState& d = devices_[device];
  if (d.due) return;  // held back already: tick() reports the newest values then
  if (changes(device, now).empty()) return;
  if (now.mono >= d.last_data + options_.min_interval) {
    report(device, now, sink);
  } else {
    d.due = d.last_data + options_.min_interval;
  }
}

void EdgeNode::tick(const Now& now, Sink& sink) {
  if (state_ != SessionState::online) {
    for (std::size_t i = 0; i < devices_.size(); ++i) {
      DeviceState& d = devices_[i];
      if (!d.due || now.mono < *d.due) continue;
      d.due.reset();
      if (d.alive && !changes(i, now).empty()) report(i, now, sink);
    }
    return;
  }
  if (rebirth_due_ && now.mono >= *rebirth_due_) {
    last_rebirth_ = now.mono;
    rebirth(now, sink);
  }
  for (std::size_t i = 0; i < devices_.size(); ++i) {
    DeviceState& d = devices_[i];
    if (!d.due || now.mono < *d.due) continue;
    d.due.reset();
    if (d.born && !changes(i, now).empty()) report(i, now, sink);
  }
}

std::optional<TimePoint> EdgeNode::wake_at() const {
  std::optional<TimePoint> at = rebirth_due_;
  for (const DeviceState& d : devices_) {
    if (d.due && (!at || *d.due < *at)) at = d.due;
  }
  return at;
}

std::vector<std::size_t> EdgeNode::changes(std::size_t device, const Now& now) const {
  const DeviceState& d = devices_[device];
  const auto& metrics = defs_[device].metrics;
  const bool counters_due = now.mono >= d.last_counters + options_.counter_interval;
  std::vector<std::size_t> out;
  for (std::size_t j = 0; j < metrics.size(); ++j) {
    if (metrics[j].counter && !counters_due) continue;
    if (moved(metrics[j], d.published[j], d.latest[j])) out.push_back(j);
  }
  return out;
}

// Online: the DDATA of what changed. Otherwise, with store_forward, the same kept for later, as
// is a DDATA the client refused (its session just ended): from here on the values count as
// reported, and the change would be in no DDATA at all.
void EdgeNode::report(std::size_t device, const Now& now, Sink& sink) {
  DeviceState& d = devices_[device];
  const auto changed = changes(device, now);
  if (changed.empty()) return;
  const bool online = state_ == SessionState::online;
  Payload p;
  p.timestamp = now.unix_ms;
  bool counters = false;
  for (const std::size_t j : changed) {
    const MetricDef& def = defs_[device].metrics[j];
    p.metrics.push_back(device_metric(device, j, false));
    p.metrics.back().historical = !online;
    d.published[j] = d.latest[j];
    counters = counters || def.counter;
  }
  d.last_data = now.mono;
  if (counters) d.last_counters = now.mono;
  if (online) {
    if (send(MessageType::ddata, defs_[device].name, p, sink) || !options_.store_forward) return;
    p.seq.reset();  // the session's, given again at replay
    for (Metric& m : p.metrics) m.historical = true;
  }
  sink.store(defs_[device].name, p);
}

// A sample while not online, with store_forward: the device's first is kept whole (what it was
// when the record begins), later ones by the DDATA rules.
void EdgeNode::keep(std::size_t device, const Now& now, Sink& sink) {
  DeviceState& d = devices_[device];
  if (!options_.store_forward || !d.alive) return;
  if (d.published.size() != d.latest.size()) {
    d.published.assign(d.latest.size(), MetricValue{});  // every metric differs from null
    d.last_counters = now.mono - options_.counter_interval;
    d.last_data = now.mono - options_.min_interval;
  }
  report_or_hold(device, now, sink);
}

EdgeNode::Replay EdgeNode::replay(std::string_view device, Payload historical, const Now& now,
                                  Sink& sink) {
  if (state_ != SessionState::online) return Replay::not_now;
  const auto it = std::find_if(defs_.begin(), defs_.end(),
                               [&](const DeviceDef& d) { return d.name == device; });
  const auto index = static_cast<std::size_t>(it - defs_.begin());
  if (it != defs_.end() && !devices_[index].born && now.mono < online_since_ + kReplayBirthWait) {
    return Replay::not_now;  // its DBIRTH may come yet: the drive has not answered since the start
  }
  if (it == defs_.end() || !devices_[index].born) {
    ++replay_dropped_;  // a DDATA before its DBIRTH would be a protocol error (spec 6.4.x)
    return Replay::dropped;
  }
  // Only the metrics the device has now, with the datatype its DBIRTH gave them.
  std::erase_if(historical.metrics, [&](const Metric& m) {
    return std::none_of(it->metrics.begin(), it->metrics.end(), [&](const MetricDef& def) {
      return def.name == m.name && def.type == m.type;
    });
  });
  if (historical.metrics.empty()) {
    ++replay_dropped_;
    return Replay::dropped;
  }
  for (Metric& m : historical.metrics) m.historical = true;
  // Refused: the record stays first in the store, for the next attempt.
  return send(MessageType::ddata, it->name, historical, sink) ? Replay::sent : Replay::not_now;
}

// A device's metric as published: its value, stamped with when the drive reported it (spec
// 6.4.4: a metric's timestamp is the time of its value), the properties in a birth only.
Metric EdgeNode::device_metric(std::size_t device, std::size_t metric, bool birth) const {
  const MetricDef& def = defs_[device].metrics[metric];
  const DeviceState& d = devices_[device];
  Metric m{def.name,         def.type,
           d.latest[metric], birth ? def.properties : std::vector<Property>{},
           std::nullopt,     false};
  const std::uint64_t changed = metric < d.changed_ms.size() ? d.changed_ms[metric] : 0;
  if (const std::uint64_t at = std::max(d.data_ms, changed); at != 0) m.timestamp = at;
  return m;
}

void EdgeNode::rebirth(const Now& now, Sink& sink) {
  rebirth_due_.reset();
  seq_ = 0;  // the NBIRTH's seq is 0 (spec 6.4.1)
  Payload p;
  p.timestamp = now.unix_ms;
  p.metrics.push_back(bd_seq_metric(bd_seq_));
  p.metrics.push_back(
      {std::string(kRebirth), DataType::boolean, MetricValue{false}, {}, {}, false});
  p.metrics.push_back(string_metric(kVersion, options_.version));
  send(MessageType::nbirth, {}, p, sink);
  for (std::size_t i = 0; i < devices_.size(); ++i) {
    devices_[i].born = false;
    devices_[i].due.reset();
    if (devices_[i].alive) birth(i, now, sink);
  }
}

void EdgeNode::birth(std::size_t device, const Now& now, Sink& sink) {
  DeviceState& d = devices_[device];
  const DeviceDef& def = defs_[device];
  Payload p;
  p.timestamp = now.unix_ms;
  for (std::size_t j = 0; j < def.metrics.size(); ++j) {
    p.metrics.push_back(device_metric(device, j, true));
  }
  if (options_.commands) {
    p.metrics.push_back(string_metric(kCommandPoint, ""));
    p.metrics.push_back(string_metric(kCommandResult, ""));
  }
  d.published = d.latest;
  d.born = true;
  d.due.reset();
  d.last_data = now.mono;
  d.last_counters = now.mono;
  ++births_;
  send(MessageType::dbirth, def.name, p, sink);
}

void EdgeNode::death(std::size_t device, const Now& now, Sink& sink) {
  devices_[device].born = false;
  devices_[device].due.reset();
  Payload p;
  p.timestamp = now.unix_ms;
  send(MessageType::ddeath, defs_[device].name, p, sink);
}

bool EdgeNode::send(MessageType type, std::string_view device, Payload& payload, Sink& sink) {
  payload.seq = seq_;
  // A message the client refused is not out: the host must not see a gap for it.
  if (!sink.publish(topic(options_.group, type, options_.edge_node, device), payload)) return false;
  seq_ = static_cast<std::uint8_t>(seq_ + 1);  // 255 -> 0 (spec 6.4.1)
  return true;
}

void EdgeNode::command(std::string_view device, std::string_view payload, const Now& now,
                       Sink& sink) {
  const auto it = std::find_if(defs_.begin(), defs_.end(),
                               [&](const DeviceDef& d) { return d.name == device; });
  std::optional<Payload> p;  // once decoded
  const auto refuse = [&](Refusal kind, const std::string& why) {
    sink.refused(make_refusal(device, p ? asked(*p) : asked(payload), kind, why));
  };
  if (it == defs_.end()) {
    refuse(Refusal::unknown_device, "no such device");
    return;
  }
  const auto index = static_cast<std::size_t>(it - defs_.begin());
  if (!options_.commands) {
    refuse(Refusal::commands_off, "[mqtt] commands = false");
    return;
  }
  // Spec 5.x: commands belong to a session where the node (and the device) is born. There is no
  // DDATA to answer with before the device's DBIRTH: the refusal is logged and audited only.
  if (const std::string refused = not_born(index); !refused.empty()) {
    refuse(Refusal::not_born, refused);
    return;
  }
  std::string why;
  p = decode(payload, why);
  if (!p) {
    refuse(Refusal::malformed, why);
    return;
  }
  if (p->metrics.size() > kMaxCommandMetrics) {
    const std::string refused = std::to_string(p->metrics.size()) + " metrics, more than the " +
                                std::to_string(kMaxCommandMetrics) + " one command may carry";
    refuse(Refusal::malformed, refused);
    command_done(index, "<" + std::to_string(p->metrics.size()) + " metrics>",
                 "refused: " + refused, now, sink);
    return;
  }
  std::vector<PointCommand> points;
  std::string names;
  std::string refused;
  Refusal refusal = Refusal::malformed;
  for (const Metric& m : p->metrics) {
    names += (names.empty() ? "" : ",") + (m.name.empty() ? std::string("<alias>") : m.name);
    const auto& metrics = it->metrics;
    const auto def = std::find_if(metrics.begin(), metrics.end(),
                                  [&](const MetricDef& d) { return d.name == m.name; });
    if (m.name.empty()) {
      refused = "metrics must be named (drivegate publishes no aliases)";
      refusal = Refusal::unknown_metric;
    } else if (def == metrics.end()) {
      refused = "no metric '" + m.name + "'";
      refusal = Refusal::unknown_metric;
    } else if (!def->writable) {
      refused = "'" + m.name + "' is read-only";
      refusal = Refusal::unknown_metric;
    } else if (std::holds_alternative<std::monostate>(m.value) ||
               std::holds_alternative<std::string>(m.value)) {
      refused = "'" + m.name + "' needs a number or a boolean";
      refusal = Refusal::wrong_type;
    } else {
      points.push_back({static_cast<std::size_t>(def - metrics.begin()), m.value});
      continue;
    }
    break;
  }
  if (points.empty() && refused.empty()) refused = "no metrics";
  if (!refused.empty()) {
    refuse(refusal, refused);
    command_done(index, names, "refused: " + refused, now, sink);
    return;
  }
  sink.write(index, std::move(points));
}

std::string EdgeNode::not_born(std::size_t device) const {
  switch (state_) {
    case SessionState::offline:
      return "the edge node is not born: its session has ended";
    case SessionState::waiting_for_host:
      return "the edge node is not born on this broker: primary host '" +
             printable(options_.primary_host, kNameMax) + "' is not online here (" +
             (host_said_offline_ ? "its STATE says offline" : "no STATE from it yet") + ")";
    case SessionState::online:
      break;
  }
  if (device < devices_.size() && !devices_[device].born) {
    return "device '" + printable(defs_[device].name, kNameMax) +
           "' is not born in this session (not heard from, or comm_lost)";
  }
  return {};
}

std::optional<Payload> as_history(MessageType type, const Payload& published) {
  if (type != MessageType::dbirth && type != MessageType::ddata) return std::nullopt;
  Payload out;
  out.timestamp = published.timestamp;
  for (const Metric& m : published.metrics) {
    if (m.historical || m.name == kCommandPoint || m.name == kCommandResult) continue;
    Metric h = m;
    h.properties.clear();
    h.historical = true;
    out.metrics.push_back(std::move(h));
  }
  if (out.metrics.empty()) return std::nullopt;
  return out;
}

void EdgeNode::command_done(std::size_t device, std::string points, std::string result,
                            const Now& now, Sink& sink) {
  if (device >= devices_.size() || !devices_[device].born || state_ != SessionState::online) {
    return;  // its DBIRTH is not out: there is nothing to report it against
  }
  Payload p;
  p.timestamp = now.unix_ms;
  p.metrics.push_back(string_metric(kCommandPoint, std::move(points)));
  p.metrics.push_back(string_metric(kCommandResult, std::move(result)));
  send(MessageType::ddata, defs_[device].name, p, sink);
}

}  // namespace drivegate::sparkplug
