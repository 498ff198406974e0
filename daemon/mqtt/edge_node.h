// A Sparkplug B 3.0 edge node (spec chapter 5, "Operational Behavior"), as a state machine with
// no I/O and no clock: the MQTT session's events, the devices' samples and the host's messages go
// in; what to publish, what to write to a drive and when to drop the session come out through a
// Sink. The northbound (northbound.cpp) feeds it from the broker and the gateway; the tests feed
// it by hand on simulated time.
//
//   connect      begin_connect() gives the NDEATH will with the session's bdSeq; subscriptions()
//   online       NBIRTH (seq 0, bdSeq, Node Control/Rebirth), a DBIRTH per device heard from
//   data         DDATA by exception: deadband per metric, at most one per device per
//                min_interval, counters at most once per counter_interval; seq 0..255 across
//                every message of the node
//   deaths       DDEATH when a device goes comm_lost, DBIRTH when it is back
//   rebirth      on NCMD Node Control/Rebirth = true (at most one per kRebirthInterval, the
//                requests in between answered by one rebirth when it has passed), or when the
//                device set changed
//   primary host with primary_host set: births wait for its STATE online; STATE offline
//                publishes NDEATH and drops the session (spec 5.13); each broker's STATEs are a
//                sequence of their own; an ONLINE older than the last ONLINE seen on that broker,
//                or an offline older than it, is stale; an offline never makes a later genuine
//                ONLINE look stale; a STATE stamped more than kStateClockTolerance ahead of this
//                clock is ignored; the 3.0 JSON form, or the 2.2 ONLINE / OFFLINE text where
//                configured (sparkplug.h)
//   commands     DCMD: carried out only while the node is born in this session (online) and the
//                device is born in it; metrics checked here (known, writable, a value, at most
//                kMaxCommandMetrics), written by the Sink, the outcome published as the device's
//                Command/Last Point and Command/Last Result; a retained NCMD or DCMD (a command
//                replayed at every subscription) is never carried out
//   timestamps   each device metric carries the time of the drive's state it shows (the last
//                reply that carried it, never a write's echo), or, for a value a write changed
//                after that reply, when the sample saw it change; the payload's is when it was
//                sent
//   store and    with store_forward, changes while not online go to Sink::store by the DDATA
//   forward      rules, and so does a DDATA of changes Sink::publish refused (not a command's
//                result: it answers a DCMD of the session that ended); replay() publishes them
//                later as historical DDATA (spec 6.4.x), a device's once its DBIRTH is out (waiting
//                for it at most kReplayBirthWait); as_history() is what a message published on a
//                link that turned out dead says about the past, to be kept the same way
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "drivegate/driver.h"
#include "mqtt/sparkplug.h"

namespace drivegate::sparkplug {

// What one metric of a device is, fixed between births.
// A command is carried out only when it is live: a DCMD published with retain would otherwise
// run a motor again at every reconnect.
inline constexpr std::size_t kMaxCommandMetrics = 64;  // more in one DCMD: refused whole
inline constexpr Millis kRebirthInterval{5'000};       // between rebirths a host asks for
// A primary host's STATE stamped further ahead of this node's clock than this is not believed:
// it would make every later genuine STATE look stale.
inline constexpr std::chrono::milliseconds kStateClockTolerance{5 * 60 * 1000};
// A kept change of a device that is not born (yet) in the session waits this long after the
// session's births for the device's DBIRTH (a drive slow to answer after a restart), then is
// dropped (counted): a device that stays dead must not hold the rest of the store back for ever.
inline constexpr Millis kReplayBirthWait{30'000};

struct MetricDef {
  std::string name;
  DataType type = DataType::unknown;
  std::vector<Property> properties;  // sent in the DBIRTH only
  double deadband = 0.0;             // a number is reported once it moved this far; 0: any change
  bool counter = false;              // reported at most once per counter_interval
  bool writable = false;             // a DCMD may write it
  bool operator==(const MetricDef&) const = default;
};

struct DeviceDef {
  std::string name;  // the Sparkplug device id
  std::vector<MetricDef> metrics;
  bool operator==(const DeviceDef&) const = default;
};

// Now, on both clocks: the steady one for intervals, Unix milliseconds for payload timestamps.
struct Now {
  TimePoint mono;
  std::uint64_t unix_ms = 0;
};

// One point of a DCMD, checked: metrics[index] of the device, to take `value`.
struct PointCommand {
  std::size_t index;
  MetricValue value;
};

// What a notice is about: the northbound throttles its log lines per kind.
enum class Notice : std::uint8_t { command, retained, host_state, rebirth };
inline constexpr std::size_t kNoticeKinds = 4;

// Why the edge node refused a DCMD itself, before it reached any drive's write path.
enum class Refusal : std::uint8_t {
  retained,        // the broker kept it: an old command, not a host asking now (spec 6.4)
  unknown_device,  // no device of that name
  commands_off,    // [mqtt] commands = false
  malformed,       // not a Sparkplug payload, or more metrics than one command may carry
  unknown_metric,  // no metric of that name (or none named: an alias), or a read-only one
  wrong_type,      // a null or a string where a number or a boolean is needed
  not_born,        // the node is not born in this session (primary host not online), or the
                   // device is not (no DBIRTH: not heard from, or comm_lost)
};

// A DCMD refused by the edge node (Sink::refused). Anyone on the broker writes what it says: its
// text is printable (other bytes shown as '?') and bounded.
struct RefusedCommand {
  std::string device;  // as its topic names it (at most 64 characters, then "...")
  // What it asked, as far as the payload could be read: "command=1 setpoint_rpm=800" (each
  // metric's name and value as they came); "<N bytes>" when it could not be read at all.
  std::string points;
  Refusal refusal = Refusal::malformed;
  std::string why;  // "no metric 'x'" (at most 256 characters, then "...")
};

class Sink {
 public:
  virtual ~Sink() = default;
  // QoS 0. Whether the MQTT client took it: not, when the session has just ended (the edge node
  // hears of that only after), and then the message is not out.
  virtual bool publish(const std::string& topic, const Payload& payload) = 0;
  // STATE offline: NDEATH was published; the session must end (and be made again later).
  virtual void drop_session() = 0;
  // Store and forward (EdgeNodeOptions::store_forward): a device's changes while there is no
  // session, or whose DDATA publish() refused, as the DDATA they would have been (metrics
  // historical, stamped with their time); replayed later through EdgeNode::replay().
  virtual void store(std::string_view device, const Payload& historical) = 0;
  // STATE offline while the births wait for the host: nothing was published in this session.
  // Where there is another broker, the host may be online there (docs/mqtt.md).
  virtual void host_offline_before_births() = 0;
  // Write `points` of device `device` in one request; answer with EdgeNode::command_done.
  virtual void write(std::size_t device, std::vector<PointCommand> points) = 0;
  // Something the log should say (a bad STATE or NCMD payload), anyone on the broker can cause:
  // throttled per kind.
  virtual void notice(Notice kind, std::string message) = 0;
  // A DCMD refused before any write path saw it: for the log as a notice does, and for the audit
  // trail, which records every write that reaches the gateway, refused or not (docs/audit.md).
  virtual void refused(RefusedCommand command) = 0;
};

struct EdgeNodeOptions {
  std::string group;
  std::string edge_node;
  std::string primary_host;  // empty: do not wait for a primary host application
  HostStateForm host_state = HostStateForm::v3_0;  // the STATE the primary host publishes
  Millis min_interval{100};
  Millis counter_interval{10'000};
  bool commands = false;
  std::string version;  // Node Info/Version
  // The bdSeq of this node's previous session (kept across restarts, mqtt/bd_seq_file.h, or
  // across a reload): the first begin_connect() goes one on from it. Nothing: the first is 0.
  std::optional<std::uint8_t> last_bd_seq;
  // Keep the changes seen while not online (Sink::store), by the same rules as DDATA (deadband,
  // min_interval, counter_interval), from each device's first sample on.
  bool store_forward = false;
};

enum class SessionState : std::uint8_t { offline, waiting_for_host, online };
std::string_view to_string(SessionState s);

// The metric names drivegate adds (spec 6.4.19 for the first two).
inline constexpr std::string_view kBdSeq = "bdSeq";
inline constexpr std::string_view kRebirth = "Node Control/Rebirth";
inline constexpr std::string_view kVersion = "Node Info/Version";
inline constexpr std::string_view kCommandPoint = "Command/Last Point";
inline constexpr std::string_view kCommandResult = "Command/Last Result";

class EdgeNode {
 public:
  explicit EdgeNode(EdgeNodeOptions options);

  // Before each MQTT CONNECT: the next bdSeq (0 first, or one on from options.last_bd_seq; +1
  // mod 256 each time, spec 6.4.19) and the NDEATH to register as the will (QoS 1, not
  // retained) under will_topic().
  Payload begin_connect(const Now& now);
  [[nodiscard]] std::string will_topic() const;
  // What to subscribe to once connected (QoS 1): NCMD, DCMD for every device, STATE if waiting
  // for a primary host.
  [[nodiscard]] std::vector<std::string> subscriptions() const;

  // The session is up on broker `broker` (its place in the list of brokers: each broker's STATEs
  // are a sequence of their own).
  void connected(const Now& now, Sink& sink, std::size_t broker = 0);
  void connection_lost();
  // A message from the broker on one of subscriptions(); `retained`: delivered from the broker's
  // store at subscription, not live (MQTT 3.1.1 section 3.3.1.3).
  void message(std::string_view topic, std::string_view payload, const Now& now, Sink& sink,
               bool retained = false);

  // The devices and their metrics. Unchanged: nothing happens. Changed while online: DDEATH for
  // each device gone, then a rebirth. Returns whether they changed.
  bool set_devices(std::vector<DeviceDef> devices, const Now& now, Sink& sink);
  // A device's state now: `alive` (heard from and not comm_lost), its values in the order of its
  // DeviceDef's metrics, and when the drive last reported its state (Unix ms; 0: never).
  void sample(std::size_t device, bool alive, std::vector<MetricValue> values,
              std::uint64_t data_ms, const Now& now, Sink& sink);
  // A written command settled: `result` is "ok" or why not.
  void command_done(std::size_t device, std::string points, std::string result, const Now& now,
                    Sink& sink);
  // A change kept while there was no session (Sink::store), published now as historical DDATA
  // after this session's births: sent; not_now (no session online, Sink::publish refused it, or
  // its device is not born yet and the session's births are less than kReplayBirthWait old: keep
  // it); or dropped (counted in replay_dropped()) because the device is unknown now or still not
  // born, or none of its metrics is one of the device's now.
  enum class Replay : std::uint8_t { sent, not_now, dropped };
  Replay replay(std::string_view device, Payload historical, const Now& now, Sink& sink);
  // Publishes the changes held back by min_interval whose time has come.
  void tick(const Now& now, Sink& sink);
  // When tick() has something to do; nullopt: nothing held back.
  [[nodiscard]] std::optional<TimePoint> wake_at() const;

  // An NDEATH for this session now (QoS 1 under will_topic()): published before a clean
  // DISCONNECT, after which the broker drops the will.
  [[nodiscard]] Payload node_death(const Now& now) const;

  [[nodiscard]] SessionState state() const { return state_; }
  [[nodiscard]] std::uint8_t bd_seq() const { return bd_seq_; }
  [[nodiscard]] const std::vector<DeviceDef>& devices() const { return defs_; }
  [[nodiscard]] std::uint64_t births() const { return births_; }
  // Commands never carried out because they came retained (NCMD and DCMD).
  [[nodiscard]] std::uint64_t retained_ignored() const { return retained_ignored_; }
  [[nodiscard]] std::uint64_t replay_dropped() const { return replay_dropped_; }
  // Rebirths asked for while one was too recent, answered together later.
  [[nodiscard]] std::uint64_t rebirths_coalesced() const { return rebirths_coalesced_; }

 private:
  struct DeviceState {
    bool alive = false;
    bool born = false;  // its DBIRTH went out in this session
    std::vector<MetricValue> latest;
    std::vector<MetricValue> published;
    std::uint64_t data_ms = 0;  // when the drive last reported its state (Unix ms)
    // Per metric: when a sample saw it change without a new reply from the drive (a write), Unix
    // ms; 0: never. A metric's time is the later of this and data_ms.
    std::vector<std::uint64_t> changed_ms;
    TimePoint last_data{};
    TimePoint last_counters{};
    std::optional<TimePoint> due;  // changes held back until then
  };

  void rebirth(const Now& now, Sink& sink);
  void rebirth_requested(const Now& now, Sink& sink);
  [[nodiscard]] Metric device_metric(std::size_t device, std::size_t metric, bool birth) const;
  void birth(std::size_t device, const Now& now, Sink& sink);
  void death(std::size_t device, const Now& now, Sink& sink);
  void report(std::size_t device, const Now& now, Sink& sink);
  void keep(std::size_t device, const Now& now, Sink& sink);
  void report_or_hold(std::size_t device, const Now& now, Sink& sink);
  std::vector<std::size_t> changes(std::size_t device, const Now& now) const;
  void command(std::string_view device, std::string_view payload, const Now& now, Sink& sink);
  // Why a command cannot be carried out now, or "" (the node and `device` are born).
  [[nodiscard]] std::string not_born(std::size_t device) const;
  void host_state(std::string_view payload, const Now& now, Sink& sink);
  // Publishes `payload` with the next seq: whether the Sink took it (if not, the seq is unused).
  bool send(MessageType type, std::string_view device, Payload& payload, Sink& sink);

  EdgeNodeOptions options_;
  SessionState state_ = SessionState::offline;
  std::uint8_t bd_seq_;  // begin_connect() makes the next
  std::uint8_t seq_ = 0;
  // Per broker: the timestamp of the newest ONLINE STATE believed there (an offline older than it
  // is a late copy of an earlier session's); `broker_` is the session's.
  std::vector<std::uint64_t> host_online_;
  std::size_t broker_ = 0;
  bool host_said_offline_ = false;  // the last STATE believed in this session said offline
  TimePoint online_since_{};        // when this session's births went out
  std::vector<DeviceDef> defs_;
  std::vector<DeviceState> devices_;
  std::uint64_t births_ = 0;
  std::optional<TimePoint> last_rebirth_;  // the last rebirth a host asked for
  std::optional<TimePoint> rebirth_due_;   // a host's rebirth request held back until then
  std::uint64_t retained_ignored_ = 0;
  std::uint64_t rebirths_coalesced_ = 0;
  std::uint64_t replay_dropped_ = 0;
};

// What a message the edge node published says about the devices' past, as the historical DDATA
// Sink::store keeps: for a DBIRTH or a live DDATA, its device metrics (not Command/...), each
// flagged historical, without properties or seq; nullopt for any other message or when nothing
// remains. Store and forward keeps it when the link it went out on turns out dead before the broker
// confirmed it (store_forward.h).
std::optional<Payload> as_history(MessageType type, const Payload& published);

}  // namespace drivegate::sparkplug
