// Fuzz target: what a broker may deliver to drivegate's Sparkplug edge node (daemon/mqtt): NCMD,
// DCMD for known and unknown devices, the primary host's STATE, anything else, interleaved with
// device samples and ticks, on simulated time.
//
// Invariants: nothing is published while offline; the first message of a session is an NBIRTH
// with seq 0, and each message after it has the seq after the one before (mod 256) until the next
// NBIRTH; NDEATHs carry no seq and the session's bdSeq; device messages name a configured device;
// a write is asked only with commands on, for a writable metric of that device, from a live
// message (never a retained one), with at most kMaxCommandMetrics points; every payload encodes
// and decodes back to the same metrics.
//
// Input: one option byte (bit 0 commands, bit 1 primary host), then steps until the input ends:
//   u8 kind: 0 NCMD, 1 DCMD device a, 2 DCMD device b, 3 DCMD unknown device, 4 STATE,
//            5 another node's NCMD, 6 sample (next byte: device, alive, a value), 7 tick,
//            8 connection lost + reconnect
//   u8 length (bit 7: delivered retained), then that many payload bytes (kinds 0..5)
#include <cstddef>
#include <cstdint>
#include <string>

#include "check.h"
#include "fuzz_input.h"
#include "mqtt/edge_node.h"
#include "mqtt/sparkplug_codec.h"

namespace {

using namespace drivegate;
using namespace drivegate::sparkplug;

class CheckingSink : public Sink {
 public:
  explicit CheckingSink(const EdgeNode& node) : node_(node) {}
  bool publish(const std::string& topic, const Payload& p) override {
    FUZZ_CHECK(node_.state() != SessionState::offline ||
               topic.find("/NDEATH/") != std::string::npos);
    const auto t = parse_topic(topic);
    FUZZ_CHECK(t.has_value());
    if (t->type == MessageType::ndeath) {
      FUZZ_CHECK(!p.seq);
      FUZZ_CHECK(p.metrics.size() == 1 &&
                 p.metrics[0].value == MetricValue{std::uint64_t{node_.bd_seq()}});
    } else {
      FUZZ_CHECK(p.seq.has_value());
      if (t->type == MessageType::nbirth) {
        FUZZ_CHECK(*p.seq == 0);
      } else {
        FUZZ_CHECK(last_seq_ >= 0 && *p.seq == static_cast<std::uint64_t>((last_seq_ + 1) % 256));
      }
      last_seq_ = static_cast<int>(*p.seq);
    }
    if (!t->device.empty()) FUZZ_CHECK(t->device == "a" || t->device == "b");
    std::string why;
    const auto back = decode(encode(p), why);
    FUZZ_CHECK(back.has_value() && back->metrics.size() == p.metrics.size());
    for (std::size_t i = 0; i < p.metrics.size(); ++i) {
      FUZZ_CHECK(back->metrics[i].name == p.metrics[i].name);
    }
    return true;  // a session that never ends under it: every message is taken
  }
  void drop_session() override { last_seq_ = -1; }
  void host_offline_before_births() override {}
  void store(std::string_view /*device*/, const Payload& /*historical*/) override {}
  void write(std::size_t device, std::vector<PointCommand> points) override {
    FUZZ_CHECK(commands && !retained && device < 2 && !points.empty());
    FUZZ_CHECK(points.size() <= kMaxCommandMetrics);
    for (const auto& pc : points) {
      FUZZ_CHECK(pc.index < node_.devices()[device].metrics.size());
      FUZZ_CHECK(node_.devices()[device].metrics[pc.index].writable);
    }
    pending.emplace_back(device, points.size());
  }
  void notice(Notice, std::string) override {}
  // What the audit trail gets of a refused DCMD: bounded, printable, and the right reason for a
  // retained one or one while commands are off.
  void refused(RefusedCommand c) override {
    FUZZ_CHECK(!c.points.empty() && c.points.size() <= 400 && !c.why.empty());
    FUZZ_CHECK(c.why.size() <= 259 && c.device.size() <= 67);
    for (const std::string* text : {&c.points, &c.why, &c.device}) {
      for (const char ch : *text) FUZZ_CHECK(ch >= 0x20 && ch < 0x7F);
    }
    if (retained) FUZZ_CHECK(c.refusal == Refusal::retained);
    if (!retained && !commands) {
      FUZZ_CHECK(c.refusal == Refusal::commands_off || c.refusal == Refusal::unknown_device);
    }
  }
  void lost() { last_seq_ = -1; }

  bool commands = false;
  bool retained = false;  // the message being delivered
  std::vector<std::pair<std::size_t, std::size_t>> pending;

 private:
  const EdgeNode& node_;
  int last_seq_ = -1;
};

std::vector<DeviceDef> devices() {
  std::vector<DeviceDef> d;
  for (const char* name : {"a", "b"}) {
    DeviceDef def{name, {}};
    MetricDef speed{"speed_rpm", DataType::int16, {}, 0.0, false, false};
    MetricDef setpoint{"setpoint_rpm", DataType::int16, {}, 0.0, false, true};
    MetricDef frames{"frames_good", DataType::int64, {}, 0.0, true, false};
    def.metrics = {speed, setpoint, frames};
    d.push_back(def);
  }
  return d;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::FuzzInput in(data, size);
  const std::uint8_t options = in.u8();
  EdgeNodeOptions o;
  o.group = "g";
  o.edge_node = "e";
  o.commands = (options & 1) != 0;
  if ((options & 2) != 0) o.primary_host = "h";
  EdgeNode node(o);
  CheckingSink sink(node);
  sink.commands = o.commands;
  TimePoint t{};
  const auto now = [&] { return Now{t, 1'700'000'000'000}; };
  node.set_devices(devices(), now(), sink);
  node.begin_connect(now());
  node.connected(now(), sink);
  while (!in.empty()) {
    const std::uint8_t kind = in.u8() % 9;
    t += Millis(in.u8());
    if (kind == 6) {
      const std::uint8_t b = in.u8();
      const auto v = static_cast<std::int64_t>(static_cast<std::int8_t>(in.u8()));
      node.sample(b & 1, (b & 2) != 0, {MetricValue{v}, MetricValue{v * 2}, MetricValue{v}}, 0,
                  now(), sink);
      continue;
    }
    if (kind == 7) {
      node.tick(now(), sink);
      // Writes settle in their turn.
      for (const auto& [device, n] : sink.pending)
        node.command_done(device, "x", "ok", now(), sink);
      sink.pending.clear();
      continue;
    }
    if (kind == 8) {
      node.connection_lost();
      sink.lost();
      node.begin_connect(now());
      node.connected(now(), sink);
      continue;
    }
    const std::uint8_t length = in.u8();
    const bool retained = (length & 0x80) != 0;  // delivered from the broker's store
    const auto payload = in.bytes(length & 0x7F);
    const std::string_view bytes(reinterpret_cast<const char*>(payload.data()), payload.size());
    static constexpr const char* kTopics[] = {"spBv1.0/g/NCMD/e",   "spBv1.0/g/DCMD/e/a",
                                              "spBv1.0/g/DCMD/e/b", "spBv1.0/g/DCMD/e/z",
                                              "spBv1.0/STATE/h",    "spBv1.0/g/NCMD/other"};
    sink.retained = retained;
    node.message(kTopics[kind], bytes, now(), sink, retained);
    sink.retained = false;
    if (node.state() == SessionState::offline) {  // STATE offline dropped the session
      sink.lost();
      node.begin_connect(now());
      node.connected(now(), sink);
    }
  }
  return 0;
}
