// The Sparkplug edge node on simulated time: births, sequence numbers, report by exception,
// deaths, rebirth, the primary host's STATE and commands, recorded from its Sink.
#include "mqtt/edge_node.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "mqtt/sparkplug_codec.h"
#include "mqtt/store_forward.h"
#include "temp_dir.h"

namespace drivegate::sparkplug {
namespace {

using namespace std::chrono_literals;
using ::testing::ElementsAre;
using ::testing::HasSubstr;

// A sample whose drive state has no time of its own: its metrics carry no timestamp.
constexpr std::uint64_t kNoData = 0;

struct Sent {
  std::string topic;
  Payload payload;
  [[nodiscard]] std::vector<std::string> names() const {
    std::vector<std::string> n;
    for (const auto& m : payload.metrics) n.push_back(m.name);
    return n;
  }
  [[nodiscard]] const Metric* metric(std::string_view name) const {
    for (const auto& m : payload.metrics) {
      if (m.name == name) return &m;
    }
    return nullptr;
  }
};

class RecordingSink : public Sink {
 public:
  bool publish(const std::string& topic, const Payload& payload) override {
    (refusing ? not_taken : sent).push_back({topic, payload});
    // As the northbound does: the client numbers what it takes, the store hears of it.
    if (!refusing && numbering != nullptr) numbering->sent(++numbered, topic, payload);
    return !refusing;
  }
  void drop_session() override { ++drops; }
  void host_offline_before_births() override { ++offline_waiting; }
  void store(std::string_view device, const Payload& historical) override {
    stored.push_back({std::string(device), historical});
  }
  void write(std::size_t device, std::vector<PointCommand> points) override {
    writes.emplace_back(device, std::move(points));
  }
  void notice(Notice, std::string message) override { notices.push_back(std::move(message)); }
  void refused(RefusedCommand c) override {
    notices.push_back("DCMD for " + c.device + " refused: " + c.why);
    refusals.push_back(std::move(c));
  }
  std::vector<Sent> take() { return std::exchange(sent, {}); }

  std::vector<Sent> sent;
  bool refusing = false;        // publish() refuses, as the MQTT client does once its session ended
  std::vector<Sent> not_taken;  // what publish() refused
  int drops = 0;
  int offline_waiting = 0;
  std::vector<Sent> stored;  // topic: the device's name
  std::vector<std::pair<std::size_t, std::vector<PointCommand>>> writes;
  std::vector<std::string> notices;
  std::vector<RefusedCommand> refusals;     // DCMDs refused before any write path, for the audit
  mqtt::StoreForward* numbering = nullptr;  // told what the client took, numbered from 1
  std::uint64_t numbered = 0;
};

MetricDef metric(std::string name, DataType type) {
  MetricDef m;
  m.name = std::move(name);
  m.type = type;
  return m;
}

// Two drives: speed (Int16), frames (a counter), setpoint (writable).
std::vector<DeviceDef> drives() {
  std::vector<DeviceDef> d;
  for (const char* name : {"washer-a", "washer-b"}) {
    DeviceDef def{name, {}};
    def.metrics.push_back(metric("speed_rpm", DataType::int16));
    auto frames = metric("frames_good", DataType::int64);
    frames.counter = true;
    def.metrics.push_back(frames);
    auto setpoint = metric("setpoint_rpm", DataType::int16);
    setpoint.writable = true;
    setpoint.properties.push_back({"engUnit", DataType::string, MetricValue{std::string("rpm")}});
    def.metrics.push_back(setpoint);
    d.push_back(std::move(def));
  }
  return d;
}

std::vector<MetricValue> values(std::int64_t speed, std::int64_t frames = 0,
                                std::int64_t setpoint = 0) {
  return {MetricValue{speed}, MetricValue{frames}, MetricValue{setpoint}};
}

class EdgeNodeTest : public ::testing::Test {
 protected:
  explicit EdgeNodeTest(EdgeNodeOptions o = options()) : node_(std::move(o)) {
    node_.set_devices(drives(), at(0ms), sink_);
  }
  static EdgeNodeOptions options() {
    EdgeNodeOptions o;
    o.group = "plant1";
    o.edge_node = "gw01";
    o.min_interval = 100ms;
    o.counter_interval = 10s;
    o.commands = true;
    o.version = "9.9";
    return o;
  }
  Now at(Millis t) const {
    return {TimePoint{} + t, 1'700'000'000'000 + static_cast<std::uint64_t>(t.count())};
  }
  // Connected, both drives heard from: NBIRTH, two DBIRTHs taken.
  void online() {
    node_.begin_connect(at(0ms));
    node_.sample(0, true, values(0), kNoData, at(0ms), sink_);
    node_.sample(1, true, values(0), kNoData, at(0ms), sink_);
    node_.connected(at(0ms), sink_);
    ASSERT_EQ(sink_.take().size(), 3u);
  }
  EdgeNode node_;
  RecordingSink sink_;
};

TEST_F(EdgeNodeTest, TheFirstConnectGoesOnFromThePreviousSessionsBdSeq) {
  // Kept across a restart (mqtt/bd_seq_file.h) or a reload: one on from it, 255 wrapping to 0.
  for (const auto& [last, first] : std::vector<std::pair<int, int>>{{0, 1}, {41, 42}, {255, 0}}) {
    auto o = options();
    o.last_bd_seq = static_cast<std::uint8_t>(last);
    EdgeNode node(o);
    node.set_devices(drives(), at(0ms), sink_);
    EXPECT_EQ(node.bd_seq(), last) << "before any connect, the last session's";
    const auto will = node.begin_connect(at(0ms));
    EXPECT_EQ(will.metrics.at(0).value, MetricValue{std::uint64_t(first)}) << last;
    EXPECT_EQ(node.bd_seq(), first);
    node.sample(0, true, values(0), kNoData, at(0ms), sink_);
    node.connected(at(0ms), sink_);
    const auto sent = sink_.take();
    ASSERT_FALSE(sent.empty());
    ASSERT_NE(sent[0].metric("bdSeq"), nullptr);
    EXPECT_EQ(sent[0].metric("bdSeq")->value, MetricValue{std::uint64_t(first)})
        << "the NBIRTH carries the will's bdSeq";
  }
}

TEST_F(EdgeNodeTest, TheWillIsAnNdeathWithTheSessionsBdSeq) {
  auto will = node_.begin_connect(at(0ms));
  EXPECT_EQ(node_.will_topic(), "spBv1.0/plant1/NDEATH/gw01");
  EXPECT_FALSE(will.seq);  // spec 6.4.1: no seq in an NDEATH
  ASSERT_EQ(will.metrics.size(), 1u);
  EXPECT_EQ(will.metrics[0].name, "bdSeq");
  EXPECT_EQ(will.metrics[0].type, DataType::uint64);
  EXPECT_EQ(will.metrics[0].value, MetricValue{std::uint64_t{0}});
  will = node_.begin_connect(at(1ms));
  EXPECT_EQ(will.metrics[0].value, MetricValue{std::uint64_t{1}});
  for (int i = 0; i < 254; ++i) node_.begin_connect(at(1ms));
  EXPECT_EQ(node_.bd_seq(), 255);
  EXPECT_EQ(node_.begin_connect(at(1ms)).metrics[0].value, MetricValue{std::uint64_t{0}});
  EXPECT_THAT(node_.subscriptions(),
              ElementsAre("spBv1.0/plant1/NCMD/gw01", "spBv1.0/plant1/DCMD/gw01/+"));
}

TEST_F(EdgeNodeTest, BirthsCarryEveryMetricAndSeqStartsAtZero) {
  node_.begin_connect(at(0ms));
  node_.sample(0, true, values(1500, 7, 1500), kNoData, at(0ms), sink_);
  node_.connected(at(5ms), sink_);
  const auto sent = sink_.take();
  ASSERT_EQ(sent.size(), 2u);  // washer-b never answered: no DBIRTH for it
  EXPECT_EQ(sent[0].topic, "spBv1.0/plant1/NBIRTH/gw01");
  EXPECT_EQ(sent[0].payload.seq, 0u);
  EXPECT_EQ(sent[0].payload.timestamp, 1'700'000'000'005u);
  EXPECT_THAT(sent[0].names(), ElementsAre("bdSeq", "Node Control/Rebirth", "Node Info/Version"));
  EXPECT_EQ(sent[0].metric("Node Control/Rebirth")->value, MetricValue{false});
  EXPECT_EQ(sent[1].topic, "spBv1.0/plant1/DBIRTH/gw01/washer-a");
  EXPECT_EQ(sent[1].payload.seq, 1u);
  EXPECT_THAT(sent[1].names(), ElementsAre("speed_rpm", "frames_good", "setpoint_rpm",
                                           "Command/Last Point", "Command/Last Result"));
  EXPECT_EQ(sent[1].metric("speed_rpm")->value, MetricValue{std::int64_t{1500}});
  EXPECT_EQ(sent[1].metric("setpoint_rpm")->properties.at(0).key, "engUnit");
  // washer-b answers later: its DBIRTH then.
  node_.sample(1, true, values(0), kNoData, at(50ms), sink_);
  const auto later = sink_.take();
  ASSERT_EQ(later.size(), 1u);
  EXPECT_EQ(later[0].topic, "spBv1.0/plant1/DBIRTH/gw01/washer-b");
  EXPECT_EQ(later[0].payload.seq, 2u);
}

TEST_F(EdgeNodeTest, DataByExceptionOnlyTheChangedMetricsAtMostOncePerInterval) {
  online();
  node_.sample(0, true, values(0), kNoData, at(200ms), sink_);  // nothing changed
  EXPECT_TRUE(sink_.take().empty());
  node_.sample(0, true, values(100), kNoData, at(210ms), sink_);
  auto sent = sink_.take();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0].topic, "spBv1.0/plant1/DDATA/gw01/washer-a");
  EXPECT_EQ(sent[0].payload.seq, 3u);
  EXPECT_THAT(sent[0].names(), ElementsAre("speed_rpm"));
  // Within min_interval: held back, and the newest value goes when it has passed.
  node_.sample(0, true, values(150), kNoData, at(250ms), sink_);
  node_.sample(0, true, values(180), kNoData, at(280ms), sink_);
  EXPECT_TRUE(sink_.take().empty());
  EXPECT_EQ(node_.wake_at(), TimePoint{} + 310ms);
  node_.tick(at(309ms), sink_);
  EXPECT_TRUE(sink_.take().empty());
  node_.tick(at(310ms), sink_);
  sent = sink_.take();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0].metric("speed_rpm")->value, MetricValue{std::int64_t{180}});
  EXPECT_EQ(sent[0].payload.seq, 4u);
  EXPECT_FALSE(node_.wake_at());
  // Another device is not held back by this one's interval.
  node_.sample(1, true, values(5), kNoData, at(311ms), sink_);
  EXPECT_EQ(sink_.take().size(), 1u);
}

TEST_F(EdgeNodeTest, DeadbandAndCounterInterval) {
  auto defs = drives();
  defs[0].metrics[0].deadband = 5;
  node_.set_devices(defs, at(0ms), sink_);
  online();
  node_.sample(0, true, values(4, 1), kNoData, at(1s), sink_);  // moved 4 < 5; frames not due
  EXPECT_TRUE(sink_.take().empty());
  node_.sample(0, true, values(-1, 2), kNoData, at(2s), sink_);  // -1 from 0: still within
  EXPECT_TRUE(sink_.take().empty());
  node_.sample(0, true, values(5, 3), kNoData, at(3s), sink_);  // 5 from the published 0
  auto sent = sink_.take();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_THAT(sent[0].names(), ElementsAre("speed_rpm"));
  node_.sample(0, true, values(5, 40), kNoData, at(10s),
               sink_);  // the counter's interval has passed
  sent = sink_.take();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_THAT(sent[0].names(), ElementsAre("frames_good"));
  node_.sample(0, true, values(5, 41), kNoData, at(11s), sink_);  // and not again for 10 s
  EXPECT_TRUE(sink_.take().empty());
}

TEST_F(EdgeNodeTest, DeathOnCommLostBirthWhenBack) {
  online();
  node_.sample(1, false, values(0), kNoData, at(1s), sink_);
  auto sent = sink_.take();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0].topic, "spBv1.0/plant1/DDEATH/gw01/washer-b");
  EXPECT_EQ(sent[0].payload.seq, 3u);
  EXPECT_TRUE(sent[0].payload.metrics.empty());
  node_.sample(1, false, values(0), kNoData, at(2s), sink_);  // still dead: said once
  EXPECT_TRUE(sink_.take().empty());
  node_.sample(1, true, values(7), kNoData, at(3s), sink_);
  sent = sink_.take();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0].topic, "spBv1.0/plant1/DBIRTH/gw01/washer-b");
  EXPECT_EQ(sent[0].metric("speed_rpm")->value, MetricValue{std::int64_t{7}});
}

TEST_F(EdgeNodeTest, SeqWrapsAfter255) {
  online();
  for (int i = 1; i <= 253; ++i)
    node_.sample(0, true, values(i), kNoData, at(Millis(1000 * i)), sink_);
  auto sent = sink_.take();
  EXPECT_EQ(sent.back().payload.seq, 255u);
  node_.sample(0, true, values(9999), kNoData, at(300s), sink_);
  EXPECT_EQ(sink_.take().at(0).payload.seq, 0u);
}

TEST_F(EdgeNodeTest, RebirthOnRequestKeepsTheBdSeq) {
  online();
  node_.sample(0, true, values(10), kNoData, at(1s), sink_);
  sink_.take();
  Payload ncmd;
  ncmd.metrics.push_back({"Node Control/Rebirth", DataType::boolean, MetricValue{true}, {}});
  node_.message("spBv1.0/plant1/NCMD/gw01", encode(ncmd), at(2s), sink_);
  const auto sent = sink_.take();
  ASSERT_EQ(sent.size(), 3u);
  EXPECT_EQ(sent[0].topic, "spBv1.0/plant1/NBIRTH/gw01");
  EXPECT_EQ(sent[0].payload.seq, 0u);
  EXPECT_EQ(sent[0].metric("bdSeq")->value, MetricValue{std::uint64_t{0}});
  EXPECT_EQ(sent[1].metric("speed_rpm")->value, MetricValue{std::int64_t{10}});
  EXPECT_EQ(sent[2].payload.seq, 2u);
  // Another edge node's NCMD, or garbage, changes nothing.
  node_.message("spBv1.0/plant1/NCMD/gw02", encode(ncmd), at(3s), sink_);
  node_.message("spBv1.0/plant1/NCMD/gw01", "\xFF\xFF", at(3s), sink_);
  EXPECT_TRUE(sink_.take().empty());
  EXPECT_THAT(sink_.notices.back(), HasSubstr("NCMD ignored"));
}

TEST_F(EdgeNodeTest, NothingIsPublishedOffline) {
  node_.sample(0, true, values(1), kNoData, at(0ms), sink_);
  EXPECT_TRUE(sink_.take().empty());
  online();
  node_.connection_lost();
  node_.sample(0, true, values(50), kNoData, at(1s), sink_);
  node_.tick(at(2s), sink_);
  EXPECT_TRUE(sink_.take().empty());
  // The next session is born afresh, with the newest values.
  node_.begin_connect(at(3s));
  node_.connected(at(3s), sink_);
  const auto sent = sink_.take();
  ASSERT_EQ(sent.size(), 3u);
  EXPECT_EQ(sent[0].metric("bdSeq")->value, MetricValue{std::uint64_t{1}});
  EXPECT_EQ(sent[1].metric("speed_rpm")->value, MetricValue{std::int64_t{50}});
}

TEST_F(EdgeNodeTest, ChangedDevicesAreARebirth) {
  online();
  auto defs = drives();
  defs.pop_back();  // washer-b removed
  EXPECT_TRUE(node_.set_devices(defs, at(1s), sink_));
  auto sent = sink_.take();
  ASSERT_EQ(sent.size(), 3u);
  EXPECT_EQ(sent[0].topic, "spBv1.0/plant1/DDEATH/gw01/washer-b");
  EXPECT_EQ(sent[1].topic, "spBv1.0/plant1/NBIRTH/gw01");
  // washer-a, defined as before, goes on as it was: alive, born again at once.
  EXPECT_EQ(sent[2].topic, "spBv1.0/plant1/DBIRTH/gw01/washer-a");
  // A device new to the set is born as it is sampled.
  defs.push_back({"washer-c", {metric("speed_rpm", DataType::int16)}});
  EXPECT_TRUE(node_.set_devices(defs, at(2s), sink_));
  sink_.take();
  node_.sample(1, true, {MetricValue{std::int64_t{3}}}, kNoData, at(2s), sink_);
  EXPECT_EQ(sink_.take().at(0).topic, "spBv1.0/plant1/DBIRTH/gw01/washer-c");
  EXPECT_FALSE(node_.set_devices(defs, at(3s), sink_));
  EXPECT_TRUE(sink_.take().empty());
}

TEST_F(EdgeNodeTest, CommandsAreCheckedThenWrittenThenReported) {
  online();
  Payload dcmd;
  dcmd.metrics.push_back({"setpoint_rpm", DataType::int16, MetricValue{std::int64_t{800}}, {}});
  node_.message("spBv1.0/plant1/DCMD/gw01/washer-b", encode(dcmd), at(1s), sink_);
  ASSERT_EQ(sink_.writes.size(), 1u);
  EXPECT_EQ(sink_.writes[0].first, 1u);
  ASSERT_EQ(sink_.writes[0].second.size(), 1u);
  EXPECT_EQ(sink_.writes[0].second[0].index, 2u);
  EXPECT_EQ(sink_.writes[0].second[0].value, MetricValue{std::int64_t{800}});
  node_.command_done(1, "setpoint_rpm", "ok", at(1100ms), sink_);
  auto sent = sink_.take();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0].topic, "spBv1.0/plant1/DDATA/gw01/washer-b");
  EXPECT_EQ(sent[0].metric("Command/Last Point")->value, MetricValue{std::string("setpoint_rpm")});
  EXPECT_EQ(sent[0].metric("Command/Last Result")->value, MetricValue{std::string("ok")});

  // Read-only, unknown, alias-only, without a value: refused here, reported, never written.
  for (Metric bad : {Metric{"speed_rpm", DataType::int16, MetricValue{std::int64_t{1}}, {}},
                     Metric{"nope", DataType::int16, MetricValue{std::int64_t{1}}, {}},
                     Metric{"", DataType::int16, MetricValue{std::int64_t{1}}, {}},
                     Metric{"setpoint_rpm", DataType::string, MetricValue{std::string("1")}, {}}}) {
    Payload p;
    p.metrics.push_back(bad);
    node_.message("spBv1.0/plant1/DCMD/gw01/washer-a", encode(p), at(2s), sink_);
    sent = sink_.take();
    ASSERT_EQ(sent.size(), 1u) << bad.name;
    EXPECT_THAT(std::get<std::string>(sent[0].metric("Command/Last Result")->value),
                HasSubstr("refused"));
  }
  EXPECT_EQ(sink_.writes.size(), 1u);
  // An unknown device: nothing published (there is no DBIRTH to report against), refused.
  node_.message("spBv1.0/plant1/DCMD/gw01/nobody", encode(dcmd), at(3s), sink_);
  EXPECT_TRUE(sink_.take().empty());
  EXPECT_THAT(sink_.notices.back(), HasSubstr("DCMD for nobody refused: no such device"));

  // Each refusal goes to the audit trail with its reason and what it asked, as it came.
  ASSERT_EQ(sink_.refusals.size(), 5u);
  const auto& r = sink_.refusals;
  EXPECT_EQ(r[0].refusal, Refusal::unknown_metric);
  EXPECT_EQ(r[0].why, "'speed_rpm' is read-only");
  EXPECT_EQ(r[0].points, "speed_rpm=1");
  EXPECT_EQ(r[1].refusal, Refusal::unknown_metric);
  EXPECT_EQ(r[1].why, "no metric 'nope'");
  EXPECT_EQ(r[2].refusal, Refusal::unknown_metric);
  EXPECT_EQ(r[2].points, "<alias>=1");
  EXPECT_EQ(r[3].refusal, Refusal::wrong_type);
  EXPECT_EQ(r[3].points, "setpoint_rpm=\"1\"");
  EXPECT_EQ(r[4].refusal, Refusal::unknown_device);
  EXPECT_EQ(r[4].device, "nobody");
  EXPECT_EQ(r[4].points, "setpoint_rpm=800");
}

// What a refused DCMD asked is recorded as it came, but printable and bounded: anyone on the
// broker writes it, and it goes to the journal and the history.
TEST_F(EdgeNodeTest, ARefusedCommandIsRecordedPrintableAndBounded) {
  online();
  Payload dcmd;
  dcmd.metrics.push_back({"nope\n\x1b[2J", DataType::boolean, MetricValue{true}, {}});
  dcmd.metrics.push_back({"x", DataType::float64, MetricValue{0.5}, {}});
  dcmd.metrics.push_back({"y", DataType::string, MetricValue{std::string(100, 'a')}, {}});
  node_.message("spBv1.0/plant1/DCMD/gw01/washer-a", encode(dcmd), at(1s), sink_);
  ASSERT_EQ(sink_.refusals.size(), 1u);
  EXPECT_EQ(sink_.refusals[0].points, "nope??[2J=true x=0.5 y=\"" + std::string(32, 'a') + "...\"");
  EXPECT_EQ(sink_.refusals[0].why, "no metric 'nope??[2J'");  // the reason quotes it likewise
  // Sixty-four metrics of long names: cut short, marked so.
  Payload many;
  for (std::size_t i = 0; i < kMaxCommandMetrics; ++i) {
    many.metrics.push_back(
        {std::string(200, 'n'), DataType::int16, MetricValue{std::int64_t{1}}, {}});
  }
  node_.message("spBv1.0/plant1/DCMD/gw01/washer-a", encode(many), at(2s), sink_);
  ASSERT_EQ(sink_.refusals.size(), 2u);
  EXPECT_LE(sink_.refusals[1].points.size(), 400u);
  EXPECT_THAT(sink_.refusals[1].points, testing::EndsWith(" ..."));
  EXPECT_THAT(sink_.refusals[1].points, testing::StartsWith(std::string(64, 'n') + "=1 "));
  // A device name of any length and bytes (only / + # are not allowed in a topic level).
  node_.message("spBv1.0/plant1/DCMD/gw01/" + std::string(1000, 'd') + "\r\n", encode(many), at(2s),
                sink_);
  ASSERT_EQ(sink_.refusals.size(), 3u);
  EXPECT_EQ(sink_.refusals[2].refusal, Refusal::unknown_device);
  EXPECT_EQ(sink_.refusals[2].device, std::string(64, 'd') + "...");
  sink_.refusals.pop_back();
  // Not a Sparkplug payload at all: its size.
  node_.message("spBv1.0/plant1/DCMD/gw01/washer-a", std::string("\xff\xff\xff", 3), at(3s), sink_);
  ASSERT_EQ(sink_.refusals.size(), 3u);
  EXPECT_EQ(sink_.refusals[2].refusal, Refusal::malformed);
  EXPECT_EQ(sink_.refusals[2].points, "<3 bytes>");
}

// Spec 6.4 (NCMD, DCMD): published with retain false. One the broker kept is an old command
// replayed at every subscription: never carried out, counted, noticed.
TEST_F(EdgeNodeTest, RetainedCommandsAreNeverCarriedOut) {
  online();
  Payload dcmd;
  dcmd.metrics.push_back({"setpoint_rpm", DataType::int16, MetricValue{std::int64_t{800}}, {}});
  node_.message("spBv1.0/plant1/DCMD/gw01/washer-a", encode(dcmd), at(1s), sink_, true);
  Payload ncmd;
  ncmd.metrics.push_back({"Node Control/Rebirth", DataType::boolean, MetricValue{true}, {}});
  node_.message("spBv1.0/plant1/NCMD/gw01", encode(ncmd), at(1s), sink_, true);
  EXPECT_TRUE(sink_.writes.empty());
  EXPECT_TRUE(sink_.take().empty());  // no rebirth, no command result
  EXPECT_EQ(node_.retained_ignored(), 2u);
  EXPECT_THAT(sink_.notices.back(),
              HasSubstr("NCMD on spBv1.0/plant1/NCMD/gw01 ignored: retained"));
  // The DCMD is refused for the audit trail, with what it would have done.
  ASSERT_EQ(sink_.refusals.size(), 1u);
  EXPECT_EQ(sink_.refusals[0].refusal, Refusal::retained);
  EXPECT_EQ(sink_.refusals[0].device, "washer-a");
  EXPECT_EQ(sink_.refusals[0].points, "setpoint_rpm=800");
  EXPECT_THAT(sink_.refusals[0].why, HasSubstr("retained by the broker"));
  // The same, live, is carried out.
  node_.message("spBv1.0/plant1/DCMD/gw01/washer-a", encode(dcmd), at(2s), sink_, false);
  EXPECT_EQ(sink_.writes.size(), 1u);
}

// A DCMD carries at most kMaxCommandMetrics: one with more is refused whole, nothing written.
TEST_F(EdgeNodeTest, ACommandOfTooManyMetricsIsRefusedWhole) {
  online();
  Payload dcmd;
  for (std::size_t i = 0; i <= kMaxCommandMetrics; ++i) {
    dcmd.metrics.push_back(
        {"setpoint_rpm", DataType::int16, MetricValue{static_cast<std::int64_t>(i)}, {}});
  }
  node_.message("spBv1.0/plant1/DCMD/gw01/washer-a", encode(dcmd), at(1s), sink_);
  EXPECT_TRUE(sink_.writes.empty());
  const auto sent = sink_.take();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_THAT(std::get<std::string>(sent[0].metric("Command/Last Result")->value),
              HasSubstr("refused: 65 metrics"));
  dcmd.metrics.pop_back();  // 64: within the bound
  node_.message("spBv1.0/plant1/DCMD/gw01/washer-a", encode(dcmd), at(2s), sink_);
  ASSERT_EQ(sink_.writes.size(), 1u);
  EXPECT_EQ(sink_.writes[0].second.size(), kMaxCommandMetrics);
}

// 2000 rebirth requests in two seconds: the first answered at once, the rest by one rebirth
// kRebirthInterval after it; none in between.
TEST_F(EdgeNodeTest, ARebirthStormIsAnsweredByOneRebirthEveryFewSeconds) {
  online();
  Payload ncmd;
  ncmd.metrics.push_back({"Node Control/Rebirth", DataType::boolean, MetricValue{true}, {}});
  const std::string bytes = encode(ncmd);
  const auto births = [](const std::vector<Sent>& sent) {
    return std::count_if(sent.begin(), sent.end(),
                         [](const Sent& m) { return m.topic == "spBv1.0/plant1/NBIRTH/gw01"; });
  };
  node_.message("spBv1.0/plant1/NCMD/gw01", bytes, at(1s), sink_);
  EXPECT_EQ(births(sink_.take()), 1);
  for (int i = 0; i < 1999; ++i) {
    node_.message("spBv1.0/plant1/NCMD/gw01", bytes, at(1s + Millis(i)), sink_);
  }
  EXPECT_EQ(births(sink_.take()), 0);
  EXPECT_EQ(node_.rebirths_coalesced(), 1999u);
  ASSERT_EQ(node_.wake_at(), TimePoint{} + 1s + kRebirthInterval);
  node_.tick(at(1s + kRebirthInterval - 1ms), sink_);
  EXPECT_EQ(births(sink_.take()), 0);
  node_.tick(at(1s + kRebirthInterval), sink_);
  const auto sent = sink_.take();
  EXPECT_EQ(births(sent), 1);
  EXPECT_EQ(sent.size(), 3u);  // NBIRTH and the two DBIRTHs
  EXPECT_FALSE(node_.wake_at());
}

// A metric carries the time of the drive's state it shows (spec 6.4.4); the payload the time it
// was sent.
TEST_F(EdgeNodeTest, DeviceMetricsCarryTheTimeOfTheDrivesState) {
  online();
  const std::uint64_t data_ms = at(900ms).unix_ms;
  node_.sample(0, true, values(55), data_ms, at(1s), sink_);
  const auto sent = sink_.take();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0].payload.timestamp, at(1s).unix_ms);
  EXPECT_EQ(sent[0].metric("speed_rpm")->timestamp, data_ms);
  // Through the codec too.
  std::string why;
  const auto decoded = decode(encode(sent[0].payload), why);
  ASSERT_TRUE(decoded);
  EXPECT_EQ(decoded->metrics.at(0).timestamp, data_ms);
}

class EdgeNodeNoCommands : public EdgeNodeTest {
 protected:
  EdgeNodeNoCommands()
      : EdgeNodeTest([] {
          auto o = options();
          o.commands = false;
          return o;
        }()) {}
};

TEST_F(EdgeNodeNoCommands, DcmdIsIgnoredAndBirthsHaveNoCommandMetrics) {
  node_.begin_connect(at(0ms));
  node_.sample(0, true, values(0), kNoData, at(0ms), sink_);
  node_.connected(at(0ms), sink_);
  const auto sent = sink_.take();
  EXPECT_THAT(sent.at(1).names(), ElementsAre("speed_rpm", "frames_good", "setpoint_rpm"));
  Payload dcmd;
  dcmd.metrics.push_back({"setpoint_rpm", DataType::int16, MetricValue{std::int64_t{800}}, {}});
  node_.message("spBv1.0/plant1/DCMD/gw01/washer-a", encode(dcmd), at(1s), sink_);
  EXPECT_TRUE(sink_.writes.empty());
  EXPECT_TRUE(sink_.take().empty());
  EXPECT_THAT(sink_.notices.back(), HasSubstr("commands = false"));
  ASSERT_EQ(sink_.refusals.size(), 1u);
  EXPECT_EQ(sink_.refusals[0].refusal, Refusal::commands_off);
  EXPECT_EQ(sink_.refusals[0].points, "setpoint_rpm=800");
}

class EdgeNodePrimaryHost : public EdgeNodeTest {
 protected:
  EdgeNodePrimaryHost()
      : EdgeNodeTest([] {
          auto o = options();
          o.primary_host = "scada";
          return o;
        }()) {}
  void state(bool online, std::uint64_t ts, Millis t) {
    node_.message("spBv1.0/STATE/scada",
                  std::string("{\"online\":") + (online ? "true" : "false") +
                      ",\"timestamp\":" + std::to_string(ts) + "}",
                  at(t), sink_);
  }
};

TEST_F(EdgeNodePrimaryHost, BirthsWaitForTheHostAndItsDeathEndsTheSession) {
  EXPECT_EQ(node_.subscriptions().back(), "spBv1.0/STATE/scada");
  node_.begin_connect(at(0ms));
  node_.sample(0, true, values(1), kNoData, at(0ms), sink_);
  node_.connected(at(0ms), sink_);
  EXPECT_EQ(node_.state(), SessionState::waiting_for_host);
  node_.sample(0, true, values(2), kNoData, at(10ms), sink_);
  EXPECT_TRUE(sink_.take().empty());
  // Offline while waiting: said to the sink (another broker may have the host), nothing sent.
  state(false, 50, 15ms);
  EXPECT_EQ(sink_.offline_waiting, 1);
  EXPECT_EQ(sink_.drops, 0);
  EXPECT_TRUE(sink_.take().empty());
  EXPECT_EQ(node_.state(), SessionState::waiting_for_host);
  state(true, 100, 20ms);
  auto sent = sink_.take();
  ASSERT_EQ(sent.size(), 2u);
  EXPECT_EQ(sent[0].topic, "spBv1.0/plant1/NBIRTH/gw01");
  EXPECT_EQ(sent[1].metric("speed_rpm")->value, MetricValue{std::int64_t{2}});
  // An older STATE (a late copy) is ignored.
  state(false, 99, 30ms);
  EXPECT_TRUE(sink_.take().empty());
  EXPECT_EQ(sink_.drops, 0);
  state(false, 200, 40ms);
  sent = sink_.take();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0].topic, "spBv1.0/plant1/NDEATH/gw01");
  EXPECT_EQ(sent[0].metric("bdSeq")->value, MetricValue{std::uint64_t{0}});
  EXPECT_EQ(sink_.drops, 1);
  EXPECT_EQ(node_.state(), SessionState::offline);
  // Garbage in STATE: a notice, nothing else.
  node_.message("spBv1.0/STATE/scada", "ONLINE", at(50ms), sink_);
  EXPECT_THAT(sink_.notices.back(), HasSubstr("STATE"));
}

// A STATE stamped far ahead of this node's clock would make every genuine STATE after it look
// stale: it is ignored, with a notice saying why.
TEST_F(EdgeNodePrimaryHost, AStateFromTheFutureIsIgnored) {
  node_.begin_connect(at(0ms));
  node_.sample(0, true, values(1), kNoData, at(0ms), sink_);
  node_.connected(at(0ms), sink_);
  state(false, 99'999'999'999'999, 10ms);
  EXPECT_THAT(sink_.notices.back(), HasSubstr("ahead of this gateway's clock"));
  state(true, at(20ms).unix_ms, 20ms);  // the genuine one: believed
  EXPECT_EQ(node_.state(), SessionState::online);
  EXPECT_EQ(sink_.take().size(), 2u);
  // Within the tolerance, a host clock a little ahead is fine.
  state(false, at(30ms).unix_ms + 60'000, 30ms);
  EXPECT_EQ(node_.state(), SessionState::offline);
}

// A Sparkplug 2.2 host (primary_host_version = "2.2"): STATE/<id> outside the namespace, the text
// ONLINE or OFFLINE, no timestamp; the 3.0 topic and JSON mean nothing to this node then.
class EdgeNodeLegacyHost : public EdgeNodeTest {
 protected:
  EdgeNodeLegacyHost()
      : EdgeNodeTest([] {
          auto o = options();
          o.primary_host = "scada";
          o.host_state = HostStateForm::v2_2;
          return o;
        }()) {}
};

TEST_F(EdgeNodeLegacyHost, BirthsWaitForOnlineAndOfflineEndsTheSession) {
  EXPECT_EQ(node_.subscriptions().back(), "STATE/scada");
  node_.begin_connect(at(0ms));
  node_.sample(0, true, values(1), kNoData, at(0ms), sink_);
  node_.connected(at(0ms), sink_);
  EXPECT_EQ(node_.state(), SessionState::waiting_for_host);
  // The 3.0 form on the 3.0 topic is not this host's: nothing happens.
  node_.message("spBv1.0/STATE/scada", R"({"online":true,"timestamp":1})", at(5ms), sink_);
  EXPECT_EQ(node_.state(), SessionState::waiting_for_host);
  // Anything but ONLINE / OFFLINE on its topic: a notice naming the form.
  node_.message("STATE/scada", "online", at(8ms), sink_);
  EXPECT_THAT(sink_.notices.back(), HasSubstr("ONLINE or OFFLINE (Sparkplug 2.2)"));
  EXPECT_TRUE(sink_.take().empty());
  node_.message("STATE/scada", "ONLINE", at(10ms), sink_, /*retained=*/true);
  auto sent = sink_.take();
  ASSERT_EQ(sent.size(), 2u);
  EXPECT_EQ(sent[0].topic, "spBv1.0/plant1/NBIRTH/gw01");
  EXPECT_EQ(node_.state(), SessionState::online);
  node_.message("STATE/scada", "OFFLINE", at(20ms), sink_);
  sent = sink_.take();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0].topic, "spBv1.0/plant1/NDEATH/gw01");
  EXPECT_EQ(sink_.drops, 1);
  EXPECT_EQ(node_.state(), SessionState::offline);
  // The next session waits again, and ONLINE (no timestamp to compare) is believed.
  node_.begin_connect(at(30ms));
  node_.connected(at(30ms), sink_);
  EXPECT_EQ(node_.state(), SessionState::waiting_for_host);
  node_.message("STATE/scada", "ONLINE", at(40ms), sink_);
  EXPECT_EQ(node_.state(), SessionState::online);
}

// Store and forward: while not online, changes are kept by the DDATA rules, each
// metric historical and stamped; replay() publishes them after the births, in this session's seq.
class EdgeNodeStoreForward : public EdgeNodeTest {
 protected:
  EdgeNodeStoreForward()
      : EdgeNodeTest([] {
          auto o = options();
          o.store_forward = true;
          o.counter_interval = 0ms;
          return o;
        }()) {}
};

TEST_F(EdgeNodeStoreForward, ChangesWhileOfflineAreKeptByTheDdataRules) {
  // Never connected: the first sample of each device is kept whole, the next as changes.
  node_.sample(0, true, values(100, 1, 0), 1'000, at(0ms), sink_);
  ASSERT_EQ(sink_.stored.size(), 1u);
  EXPECT_EQ(sink_.stored[0].topic, "washer-a");
  EXPECT_THAT(sink_.stored[0].names(), ElementsAre("speed_rpm", "frames_good", "setpoint_rpm"));
  for (const Metric& m : sink_.stored[0].payload.metrics) {
    EXPECT_TRUE(m.historical) << m.name;
    EXPECT_EQ(m.timestamp, 1'000u) << "the drive's time of the value";
  }
  EXPECT_FALSE(sink_.stored[0].payload.seq) << "seq is the session's, given at replay";
  EXPECT_TRUE(sink_.take().empty()) << "nothing published without a session";
  // Within min_interval (100 ms): held back, then kept by tick() with the newest value.
  node_.sample(0, true, values(200, 1, 0), 1'050, at(50ms), sink_);
  node_.sample(0, true, values(300, 1, 0), 1'080, at(80ms), sink_);
  EXPECT_EQ(sink_.stored.size(), 1u);
  ASSERT_TRUE(node_.wake_at());
  node_.tick(at(100ms), sink_);
  ASSERT_EQ(sink_.stored.size(), 2u);
  EXPECT_THAT(sink_.stored[1].names(), ElementsAre("speed_rpm"));
  EXPECT_EQ(sink_.stored[1].metric("speed_rpm")->value, MetricValue{std::int64_t{300}});
  EXPECT_EQ(sink_.stored[1].metric("speed_rpm")->timestamp, 1'080u);
  // Unchanged: nothing kept. A dead device: nothing kept.
  node_.sample(0, true, values(300, 1, 0), 1'300, at(300ms), sink_);
  node_.sample(1, false, values(5), 1'300, at(300ms), sink_);
  EXPECT_EQ(sink_.stored.size(), 2u);
}

TEST_F(EdgeNodeStoreForward, KeptChangesReplayAfterTheBirthsAsHistoricalDdata) {
  online();
  // The samples before the first session were kept too (each device's first, whole).
  ASSERT_EQ(sink_.stored.size(), 2u);
  sink_.stored.clear();
  node_.connection_lost();
  node_.sample(0, true, values(10), 2'000, at(200ms), sink_);
  node_.sample(0, true, values(20), 2'300, at(500ms), sink_);
  ASSERT_EQ(sink_.stored.size(), 2u);
  EXPECT_THAT(sink_.stored[0].names(), ElementsAre("speed_rpm")) << "relative to the last DDATA";
  // No session: replay() keeps the record.
  EXPECT_EQ(node_.replay("washer-a", sink_.stored[0].payload, at(600ms), sink_),
            EdgeNode::Replay::not_now);
  node_.begin_connect(at(1s));
  node_.connected(at(1s), sink_);
  auto sent = sink_.take();
  ASSERT_EQ(sent.size(), 3u);  // NBIRTH, DBIRTH x2
  EXPECT_EQ(node_.replay("washer-a", sink_.stored[0].payload, at(1s), sink_),
            EdgeNode::Replay::sent);
  EXPECT_EQ(node_.replay("washer-a", sink_.stored[1].payload, at(1s), sink_),
            EdgeNode::Replay::sent);
  sent = sink_.take();
  ASSERT_EQ(sent.size(), 2u);
  EXPECT_EQ(sent[0].topic, "spBv1.0/plant1/DDATA/gw01/washer-a");
  EXPECT_EQ(sent[0].payload.seq, 3u) << "this session's seq, after the births";
  EXPECT_EQ(sent[1].payload.seq, 4u);
  EXPECT_TRUE(sent[0].metric("speed_rpm")->historical);
  EXPECT_EQ(sent[0].metric("speed_rpm")->value, MetricValue{std::int64_t{10}});
  EXPECT_EQ(sent[0].metric("speed_rpm")->timestamp, 2'000u);
  EXPECT_EQ(sent[1].metric("speed_rpm")->timestamp, 2'300u);
  // A device unknown now, or a metric it no longer has: dropped, counted, nothing sent.
  EXPECT_EQ(node_.replay("washer-z", sink_.stored[0].payload, at(1s), sink_),
            EdgeNode::Replay::dropped);
  Payload other = sink_.stored[0].payload;
  other.metrics[0].name = "gone";
  EXPECT_EQ(node_.replay("washer-a", other, at(1s), sink_), EdgeNode::Replay::dropped);
  EXPECT_EQ(node_.replay_dropped(), 2u);
  EXPECT_TRUE(sink_.take().empty());
}

TEST_F(EdgeNodeTest, WithoutStoreForwardNothingIsKept) {
  node_.sample(0, true, values(100), 1'000, at(0ms), sink_);
  node_.sample(0, true, values(200), 1'000, at(500ms), sink_);
  EXPECT_TRUE(sink_.stored.empty());
}

// The client refuses a DDATA when its session has just ended, before the edge node hears of it:
// the change is then in no DDATA, unless the store keeps it.
TEST_F(EdgeNodeStoreForward, ADdataTheClientRefusesIsKeptAsHistoricalWithItsTime) {
  online();
  sink_.stored.clear();  // each device's first sample, from before the session
  sink_.refusing = true;
  node_.sample(0, true, values(100), 2'000, at(200ms), sink_);
  ASSERT_EQ(sink_.not_taken.size(), 1u);
  EXPECT_EQ(sink_.not_taken[0].topic, "spBv1.0/plant1/DDATA/gw01/washer-a");
  ASSERT_EQ(sink_.stored.size(), 1u);
  const Sent kept = sink_.stored[0];
  EXPECT_EQ(kept.topic, "washer-a");
  EXPECT_THAT(kept.names(), ElementsAre("speed_rpm"));
  EXPECT_EQ(kept.metric("speed_rpm")->value, MetricValue{std::int64_t{100}});
  EXPECT_TRUE(kept.metric("speed_rpm")->historical);
  EXPECT_EQ(kept.metric("speed_rpm")->timestamp, 2'000u) << "the drive's time of the value";
  EXPECT_EQ(kept.payload.timestamp, at(200ms).unix_ms) << "when it was to be sent";
  EXPECT_FALSE(kept.payload.seq) << "seq is the session's, given at replay";
  // The refused DDATA took no seq: the host sees none missing in what did go out.
  sink_.refusing = false;
  node_.sample(0, true, values(200), 2'300, at(500ms), sink_);
  EXPECT_EQ(node_.replay("washer-a", kept.payload, at(500ms), sink_), EdgeNode::Replay::sent);
  const auto sent = sink_.take();
  ASSERT_EQ(sent.size(), 2u);
  EXPECT_EQ(sent[0].payload.seq, 3u) << "the first after the births";
  EXPECT_FALSE(sent[0].metric("speed_rpm")->historical);
  EXPECT_EQ(sent[1].payload.seq, 4u);
  EXPECT_TRUE(sent[1].metric("speed_rpm")->historical);
  EXPECT_EQ(sent[1].metric("speed_rpm")->timestamp, 2'000u);
}

TEST_F(EdgeNodeTest, WithoutStoreForwardADdataTheClientRefusesIsDropped) {
  online();
  sink_.refusing = true;
  node_.sample(0, true, values(100), 2'000, at(200ms), sink_);
  EXPECT_EQ(sink_.not_taken.size(), 1u);
  EXPECT_TRUE(sink_.stored.empty());
  // Counted as reported: the same values again are no change.
  sink_.refusing = false;
  node_.sample(0, true, values(100), 2'000, at(500ms), sink_);
  EXPECT_TRUE(sink_.take().empty());
}

// A replay the client refuses is not_now, as offline: the store's record stays first, and the
// next attempt sends it.
TEST_F(EdgeNodeStoreForward, AReplayTheClientRefusesStaysInTheStoreForTheNextAttempt) {
  test::TempDir tmp;
  mqtt::StoreForward store(tmp / "store", mqtt::SpoolLimits{}, 100,
                           std::make_shared<spdlog::logger>("edge_node_test"));
  ASSERT_TRUE(store.open());
  online();
  ASSERT_EQ(sink_.stored.size(), 2u);  // each device's first sample, from before the session
  for (const Sent& s : sink_.stored) store.keep(s.topic, s.payload, at(0ms).unix_ms);
  sink_.refusing = true;
  EXPECT_EQ(store.replay(node_, sink_, at(1s)), 0u) << "refused: nothing taken";
  EXPECT_TRUE(store.waiting());
  EXPECT_EQ(sink_.not_taken.size(), 1u) << "the batch goes on after a refusal";
  auto stats = store.stats(node_);
  EXPECT_EQ(stats.records, 2u);
  EXPECT_EQ(stats.replayed, 0u);
  EXPECT_EQ(stats.replay_dropped, 0u);
  sink_.refusing = false;
  EXPECT_EQ(store.replay(node_, sink_, at(2s)), 2u);
  EXPECT_FALSE(store.waiting());
  const auto sent = sink_.take();
  ASSERT_EQ(sent.size(), 2u);
  EXPECT_EQ(sent[0].topic, "spBv1.0/plant1/DDATA/gw01/washer-a");
  EXPECT_EQ(sent[0].payload.seq, 3u) << "the refused attempt took no seq";
  EXPECT_EQ(sent[1].topic, "spBv1.0/plant1/DDATA/gw01/washer-b");
  stats = store.stats(node_);
  EXPECT_EQ(stats.records, 0u);
  EXPECT_EQ(stats.replayed, 2u);
}

// --- commands only in a born session -------------------------------------------------------------

// A DCMD is carried out only while the node is born here (its primary host online) and the device
// is born: while the births wait for the host, on a session that has ended, or for a device with
// no DBIRTH, it is refused with the real reason and nothing is written; an NCMD likewise does
// nothing. Where there is no DBIRTH there is no DDATA to answer with.
TEST_F(EdgeNodePrimaryHost, ACommandIsCarriedOutOnlyWhileTheNodeAndTheDeviceAreBorn) {
  Payload run;
  run.metrics.push_back({"setpoint_rpm", DataType::int16, MetricValue{std::int64_t{900}}, {}});
  Payload rebirth;
  rebirth.metrics.push_back({"Node Control/Rebirth", DataType::boolean, MetricValue{true}, {}});
  node_.begin_connect(at(0ms));
  node_.sample(0, true, values(1), kNoData, at(0ms), sink_);
  node_.connected(at(0ms), sink_);
  ASSERT_EQ(node_.state(), SessionState::waiting_for_host);
  node_.message("spBv1.0/plant1/DCMD/gw01/washer-a", encode(run), at(10ms), sink_);
  node_.message("spBv1.0/plant1/NCMD/gw01", encode(rebirth), at(10ms), sink_);
  EXPECT_TRUE(sink_.writes.empty()) << "written before the node was born";
  EXPECT_TRUE(sink_.take().empty()) << "nothing may be published before the births";
  ASSERT_EQ(sink_.refusals.size(), 1u);
  EXPECT_EQ(sink_.refusals[0].refusal, Refusal::not_born);
  EXPECT_EQ(sink_.refusals[0].points, "setpoint_rpm=900");
  EXPECT_EQ(sink_.refusals[0].why,
            "the edge node is not born on this broker: primary host 'scada' is not online here "
            "(no STATE from it yet)");
  EXPECT_THAT(sink_.notices.back(), HasSubstr("NCMD ignored: the edge node is not born"));
  // The host offline here: the reason says so.
  state(false, 50, 20ms);
  node_.message("spBv1.0/plant1/DCMD/gw01/washer-a", encode(run), at(30ms), sink_);
  ASSERT_EQ(sink_.refusals.size(), 2u);
  EXPECT_THAT(sink_.refusals[1].why, HasSubstr("its STATE says offline"));
  // Born: washer-a takes it; washer-b, never heard from, has no DBIRTH and does not.
  state(true, 100, 40ms);
  ASSERT_EQ(node_.state(), SessionState::online);
  sink_.take();
  node_.message("spBv1.0/plant1/DCMD/gw01/washer-b", encode(run), at(50ms), sink_);
  EXPECT_TRUE(sink_.writes.empty());
  ASSERT_EQ(sink_.refusals.size(), 3u);
  EXPECT_EQ(sink_.refusals[2].refusal, Refusal::not_born);
  EXPECT_EQ(sink_.refusals[2].why,
            "device 'washer-b' is not born in this session (not heard from, or comm_lost)");
  EXPECT_TRUE(sink_.take().empty()) << "no DDATA for a device without a DBIRTH";
  node_.message("spBv1.0/plant1/DCMD/gw01/washer-a", encode(run), at(60ms), sink_);
  EXPECT_EQ(sink_.writes.size(), 1u);
  // The session ended (the host went offline), a command still in the client's buffer: refused.
  state(false, 200, 70ms);
  ASSERT_EQ(node_.state(), SessionState::offline);
  node_.message("spBv1.0/plant1/DCMD/gw01/washer-a", encode(run), at(80ms), sink_);
  EXPECT_EQ(sink_.writes.size(), 1u);
  ASSERT_EQ(sink_.refusals.size(), 4u);
  EXPECT_EQ(sink_.refusals[3].why, "the edge node is not born: its session has ended");
}

// Clearing a retained command the way docs/mqtt.md says (an empty retained publish): the broker
// hands the empty message to its subscribers too. It asks nothing: no refusal in the audit trail.
TEST_F(EdgeNodeTest, AnEmptyCommandClearsARetainedOneAndAsksNothing) {
  online();
  node_.message("spBv1.0/plant1/DCMD/gw01/washer-a", "", at(1s), sink_);
  node_.message("spBv1.0/plant1/NCMD/gw01", "", at(1s), sink_);
  EXPECT_TRUE(sink_.refusals.empty()) << sink_.refusals.front().why;
  EXPECT_TRUE(sink_.writes.empty());
  EXPECT_TRUE(sink_.take().empty());
  EXPECT_THAT(sink_.notices.back(), HasSubstr("a retained command cleared"));
}

// --- the primary host's STATE, broker by broker ----------------------------------------------

// A host online on two brokers stamps each connection with its own time: each broker's STATEs are
// a sequence of their own. Online on broker 1 at T, on broker 0 at T - 1000: the node that moves
// from 1 to 0 is born there.
TEST_F(EdgeNodePrimaryHost, EachBrokersStateIsASequenceOfItsOwn) {
  const std::uint64_t t = at(0ms).unix_ms;
  node_.begin_connect(at(0ms));
  node_.sample(0, true, values(1), kNoData, at(0ms), sink_);
  node_.connected(at(0ms), sink_, 1);
  state(true, t, 10ms);
  ASSERT_EQ(node_.state(), SessionState::online);
  node_.connection_lost();  // broker 1's will, say: the node goes on to broker 0
  sink_.take();
  node_.begin_connect(at(1s));
  node_.connected(at(1s), sink_, 0);
  state(true, t - 1000, 1010ms);
  EXPECT_EQ(node_.state(), SessionState::online) << "broker 0's ONLINE taken for stale";
  EXPECT_EQ(sink_.take().size(), 2u);
  // And back on broker 1, its own sequence still holds: an older STATE there is stale.
  node_.connection_lost();
  node_.begin_connect(at(2s));
  node_.connected(at(2s), sink_, 1);
  state(false, t - 1, 2010ms);
  state(true, t - 1, 2020ms);
  EXPECT_EQ(node_.state(), SessionState::waiting_for_host);
  EXPECT_EQ(sink_.offline_waiting, 0);
}

// Anyone on the broker may publish a STATE. An offline stamped inside the tolerance (290 s ahead)
// takes the node offline, but cannot make the host's next genuine ONLINE, stamped with the host's
// own clock, look stale: the node is born again on it.
TEST_F(EdgeNodePrimaryHost, AForgedOfflineCannotHoldTheNodeOfflinePastTheHostsNextOnline) {
  node_.begin_connect(at(0ms));
  node_.sample(0, true, values(1), kNoData, at(0ms), sink_);
  node_.connected(at(0ms), sink_);
  state(true, at(0ms).unix_ms, 10ms);
  ASSERT_EQ(node_.state(), SessionState::online);
  sink_.take();
  state(false, at(0ms).unix_ms + 290'000, 1s);  // forged
  EXPECT_EQ(node_.state(), SessionState::offline);
  EXPECT_EQ(sink_.drops, 1);
  sink_.take();  // the NDEATH
  // Connected again, the forged STATE is what the broker kept.
  node_.begin_connect(at(2s));
  node_.connected(at(2s), sink_);
  state(false, at(0ms).unix_ms + 290'000, 2010ms);
  EXPECT_EQ(node_.state(), SessionState::waiting_for_host);
  // The host sees it on its own topic and says again that it is online, now.
  state(true, at(3s).unix_ms, 3s);
  EXPECT_EQ(node_.state(), SessionState::online) << "the genuine ONLINE taken for stale";
  EXPECT_EQ(sink_.take().size(), 2u);
  // An earlier session's death certificate (older than the ONLINE believed) is still stale.
  state(false, at(2s).unix_ms, 4s);
  EXPECT_EQ(node_.state(), SessionState::online);
}

// --- timestamps ----------------------------------------------------------------------------------

// A setpoint written while the drive is stopped changes no reply: the DDATA that reports it says
// when it changed, not the last poll's time, which is from before it held.
TEST_F(EdgeNodeTest, AValueAWriteChangedCarriesTheTimeItChanged) {
  online();
  const std::uint64_t poll = at(900ms).unix_ms;
  node_.sample(0, true, values(0, 0, 0), poll, at(1s), sink_);
  sink_.take();
  node_.sample(0, true, values(0, 0, 700), poll, at(5s), sink_);
  auto sent = sink_.take();
  ASSERT_EQ(sent.size(), 1u);
  ASSERT_NE(sent[0].metric("setpoint_rpm"), nullptr);
  EXPECT_EQ(sent[0].metric("setpoint_rpm")->timestamp, at(5s).unix_ms);
  // The next reply carries the drive's state with it: its time from then on.
  node_.sample(0, true, values(10, 0, 700), at(5200ms).unix_ms, at(5300ms), sink_);
  sent = sink_.take();
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0].metric("speed_rpm")->timestamp, at(5200ms).unix_ms);
  // A rebirth's DBIRTH gives each metric the later of the two.
  Payload rebirth;
  rebirth.metrics.push_back({"Node Control/Rebirth", DataType::boolean, MetricValue{true}, {}});
  node_.message("spBv1.0/plant1/NCMD/gw01", encode(rebirth), at(6s), sink_);
  sent = sink_.take();
  ASSERT_EQ(sent.size(), 3u);
  EXPECT_EQ(sent[1].metric("setpoint_rpm")->timestamp, at(5200ms).unix_ms);
}

// --- store and forward: births, reloads, delivery ------------------------------------------------

// A drive slow to answer after a restart: its kept changes wait for its DBIRTH (within
// kReplayBirthWait) instead of being dropped.
TEST_F(EdgeNodeStoreForward, AKeptChangeWaitsForItsDevicesBirth) {
  node_.sample(1, true, values(5), 1'000, at(0ms), sink_);  // kept while offline
  ASSERT_EQ(sink_.stored.size(), 1u);
  const Payload kept = sink_.stored[0].payload;
  node_.sample(1, false, values(5), 1'000, at(10ms), sink_);  // the restart: not heard from yet
  node_.begin_connect(at(1s));
  node_.connected(at(1s), sink_);
  sink_.take();
  EXPECT_EQ(node_.replay("washer-b", kept, at(1100ms), sink_), EdgeNode::Replay::not_now);
  EXPECT_EQ(node_.replay("washer-b", kept, at(20s), sink_), EdgeNode::Replay::not_now);
  EXPECT_EQ(node_.replay_dropped(), 0u);
  node_.sample(1, true, values(6), 21'000, at(21s), sink_);  // it answers: DBIRTH
  ASSERT_EQ(sink_.take().size(), 1u);
  EXPECT_EQ(node_.replay("washer-b", kept, at(21s), sink_), EdgeNode::Replay::sent);
  // One that never answers holds the rest back no longer than the bound.
  node_.sample(1, false, values(6), 21'000, at(22s), sink_);
  EXPECT_EQ(node_.replay("washer-b", kept, at(1s + kReplayBirthWait), sink_),
            EdgeNode::Replay::dropped);
  EXPECT_EQ(node_.replay_dropped(), 1u);
}

// A SIGHUP during an outage that changes the device set: the devices defined as before go on as
// they were, so what was kept of them is not kept again.
TEST_F(EdgeNodeStoreForward, AReloadDuringAnOutageKeepsNothingTwice) {
  node_.sample(0, true, values(100, 1, 0), 1'000, at(0ms), sink_);
  ASSERT_EQ(sink_.stored.size(), 1u);
  auto defs = drives();
  DeviceDef added{"washer-c", {metric("speed_rpm", DataType::int16)}};
  defs.push_back(added);
  ASSERT_TRUE(node_.set_devices(defs, at(500ms), sink_));
  node_.sample(0, true, values(100, 1, 0), 1'000, at(600ms), sink_);
  EXPECT_EQ(sink_.stored.size(), 1u) << "kept again after the reload";
  node_.sample(0, true, values(110, 1, 0), 1'700, at(700ms), sink_);
  ASSERT_EQ(sink_.stored.size(), 2u);
  EXPECT_THAT(sink_.stored[1].names(), ElementsAre("speed_rpm"));
}

TEST(AsHistory, ADbirthOrALiveDdataIsItsDeviceMetricsFlaggedHistorical) {
  Payload birth;
  birth.timestamp = 5;
  birth.seq = 3;
  birth.metrics.push_back({"speed_rpm",
                           DataType::int16,
                           MetricValue{std::int64_t{10}},
                           {{"engUnit", DataType::string, MetricValue{std::string("rpm")}}},
                           std::uint64_t{4}});
  birth.metrics.push_back(
      {std::string(kCommandResult), DataType::string, MetricValue{std::string()}, {}});
  const auto h = as_history(MessageType::dbirth, birth);
  ASSERT_TRUE(h);
  ASSERT_EQ(h->metrics.size(), 1u);
  EXPECT_EQ(h->metrics[0].name, "speed_rpm");
  EXPECT_TRUE(h->metrics[0].historical);
  EXPECT_TRUE(h->metrics[0].properties.empty());
  EXPECT_EQ(h->metrics[0].timestamp, 4u);
  EXPECT_FALSE(h->seq);
  EXPECT_TRUE(as_history(MessageType::ddata, birth));
  for (const auto type : {MessageType::nbirth, MessageType::ddeath, MessageType::ndeath}) {
    EXPECT_FALSE(as_history(type, birth));
  }
  Payload result;  // a command's result answers a DCMD of its own session: not history
  result.metrics.push_back(
      {std::string(kCommandPoint), DataType::string, MetricValue{std::string("command")}, {}});
  result.metrics.push_back(
      {std::string(kCommandResult), DataType::string, MetricValue{std::string("ok")}, {}});
  EXPECT_FALSE(as_history(MessageType::ddata, result));
}

class StoreDelivery : public EdgeNodeStoreForward {
 protected:
  StoreDelivery() : store_(tmp_ / "store", mqtt::SpoolLimits{}, 100, log()) {
    EXPECT_TRUE(store_.open());
  }
  static std::shared_ptr<spdlog::logger> log() {
    return std::make_shared<spdlog::logger>("edge_node_test");
  }
  // Online, with the store told what the client takes; the samples from before kept there.
  void online_numbered() {
    online();
    for (const Sent& s : sink_.stored) store_.keep(s.topic, s.payload, at(0ms).unix_ms);
    sink_.stored.clear();
    sink_.numbering = &store_;
  }
  // Replayed and confirmed until nothing waits: what was published.
  std::vector<Sent> drain(const Now& now) {
    std::vector<Sent> out;
    while (store_.waiting()) {
      if (store_.replay(node_, sink_, now) == 0) break;
      for (auto& x : sink_.take()) out.push_back(std::move(x));
      store_.delivered(sink_.numbered);
    }
    return out;
  }
  test::TempDir tmp_;
  mqtt::StoreForward store_;
};

// A record replayed leaves the store, and counts as replayed, only once the broker confirmed the
// message that carried it; the session lost before that, it is sent again in the next. The
// records out unconfirmed are a window that starts at one in each session and doubles with each
// confirmation.
TEST_F(StoreDelivery, ARecordLeavesTheStoreOnlyOnceTheBrokerConfirmedIt) {
  online_numbered();
  EXPECT_EQ(store_.replay(node_, sink_, at(1s)), 1u) << "a window of one record at first";
  EXPECT_TRUE(store_.window_full());
  ASSERT_EQ(sink_.take().size(), 1u);
  auto stats = store_.stats(node_);
  EXPECT_EQ(stats.records, 2u) << "not confirmed: still kept";
  EXPECT_EQ(stats.replayed, 0u);
  store_.delivered(sink_.numbered);
  stats = store_.stats(node_);
  EXPECT_EQ(stats.records, 1u);
  EXPECT_EQ(stats.replayed, 1u);
  EXPECT_FALSE(store_.window_full());
  EXPECT_EQ(store_.replay(node_, sink_, at(1s)), 1u);
  ASSERT_EQ(sink_.take().size(), 1u);
  EXPECT_EQ(store_.stats(node_).records, 1u);
  // The link dies before the second is confirmed: the next session sends it again.
  node_.connection_lost();
  store_.lost(at(2s).unix_ms);
  EXPECT_TRUE(store_.waiting());
  node_.begin_connect(at(3s));
  node_.connected(at(3s), sink_);
  sink_.take();
  store_.replay(node_, sink_, at(3s));
  const auto again = sink_.take();
  ASSERT_EQ(again.size(), 1u);
  EXPECT_EQ(again[0].topic, "spBv1.0/plant1/DDATA/gw01/washer-b");
  EXPECT_TRUE(again[0].metric("speed_rpm")->historical);
  store_.delivered(sink_.numbered);
  stats = store_.stats(node_);
  EXPECT_EQ(stats.records, 0u);
  EXPECT_EQ(stats.replayed, 2u);
  EXPECT_EQ(stats.kept, 2u);
}

// The window grows with each confirmation, up to a second's worth (per_second, 100 here).
TEST_F(StoreDelivery, TheWindowDoublesWithEachConfirmation) {
  online_numbered();
  for (int i = 0; i < 300; ++i) {
    Payload p;
    p.metrics.push_back(
        {"speed_rpm", DataType::int16, MetricValue{std::int64_t{i}}, {}, std::uint64_t(i), true});
    store_.keep("washer-a", p, at(0ms).unix_ms);
  }
  std::vector<unsigned> sent;
  for (int round = 0; round < 9; ++round) {
    sent.push_back(store_.replay(node_, sink_, at(1s), 1000));
    store_.delivered(sink_.numbered);
  }
  EXPECT_THAT(sent, ElementsAre(1u, 2u, 4u, 8u, 16u, 32u, 64u, 100u, 75u));
  EXPECT_EQ(store_.stats(node_).records, 0u);
}

// Live DDATA and births published on a link that turned out dead, not confirmed: kept as
// historical DDATA when the session is lost, and replayed in the next; confirmed ones are not.
TEST_F(StoreDelivery, LiveChangesNotConfirmedAreKeptWhenTheLinkDies) {
  online_numbered();
  drain(at(1s));
  sink_.take();
  node_.sample(0, true, values(10), 1'100, at(1100ms), sink_);  // confirmed below
  store_.delivered(sink_.numbered);
  node_.sample(0, true, values(20), 1'300, at(1300ms), sink_);  // into the dead link
  node_.sample(0, true, values(30), 1'500, at(1500ms), sink_);
  ASSERT_EQ(sink_.take().size(), 3u);
  EXPECT_EQ(store_.stats(node_).records, 0u);
  node_.connection_lost();
  store_.lost(at(9s).unix_ms);
  EXPECT_EQ(store_.stats(node_).records, 2u) << "the two changes the broker never confirmed";
  node_.begin_connect(at(10s));
  node_.connected(at(10s), sink_);
  sink_.take();
  const auto replayed = drain(at(10s));
  ASSERT_EQ(replayed.size(), 2u);
  EXPECT_EQ(replayed[0].metric("speed_rpm")->value, MetricValue{std::int64_t{20}});
  EXPECT_EQ(replayed[0].metric("speed_rpm")->timestamp, 1'300u);
  EXPECT_TRUE(replayed[0].metric("speed_rpm")->historical);
  EXPECT_EQ(replayed[1].metric("speed_rpm")->value, MetricValue{std::int64_t{30}});
  EXPECT_EQ(store_.stats(node_).records, 0u);
}

}  // namespace
}  // namespace drivegate::sparkplug
