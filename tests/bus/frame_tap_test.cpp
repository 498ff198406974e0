// The bus engine's frame tap (bus/frame_tap.h): frames as the engine sees them, a sent frame
// when sent, a received one once the station's verdict says where it ends, flagged by that
// verdict; bytes nobody can place as noise; nothing once the tap is removed.
#include <gtest/gtest.h>
#include <spdlog/logger.h>

#include <vector>

#include "bus/bus_engine.h"

namespace drivegate {
namespace {

class Clock1 final : public BusClock {
 public:
  TimePoint now() const override { return now_; }
  void set_alarm(TimePoint) override {}
  TimePoint now_{std::chrono::seconds(100)};
};

class Line1 final : public BusLine {
 public:
  void send(ByteView frame) override { sent.emplace_back(frame.begin(), frame.end()); }
  std::vector<Bytes> sent;
};

// Polls A0 01 once per call of arm(); B0 01 xx is the reply, BE 01 xx a damaged one.
class PollStation final : public Station {
 public:
  PollStation()
      : link_{LinkPolicy{},
              LinkHealth(TimePoint{}),
              {},
              nullptr,
              std::make_shared<spdlog::logger>("test")} {}
  const std::string& name() const override { return name_; }
  Link& link() override { return link_; }
  PendingWrites pending_writes(TimePoint) const override { return PendingWrites::none; }
  void on_work(std::function<void()>) override {}
  std::optional<Exchange> next_exchange(TimePoint, Turn) override {
    if (!armed_) return std::nullopt;
    armed_ = false;
    Exchange ex;
    ex.frame = {0xA0, 0x01};
    ex.attempts = 2;
    return ex;
  }
  TimePoint wake_at() const override { return TimePoint{}; }
  RxVerdict on_receive(ByteView rx, TimePoint) override {
    if (rx.size() < 3) return {RxKind::incomplete, 0};
    if (rx[0] == 0xB0) return {RxKind::reply, 3};
    if (rx[0] == 0xBE) return {RxKind::bad_checksum, 3};
    return {RxKind::noise, 1};
  }
  void on_no_reply(TimePoint) override {}
  void on_comm_lost(TimePoint) override {}
  void on_tick(TimePoint) override {}
  void arm() { armed_ = true; }

 private:
  std::string name_ = "drive";
  Link link_;
  bool armed_ = false;
};

struct Seen {
  FrameDirection direction;
  std::uint8_t flags;
  const Station* station;
  Bytes bytes;
};

class Recorder final : public FrameTap {
 public:
  void on_frame(const TappedFrame& f, TimePoint at) override {
    frames.push_back({f.direction, f.flags, f.station, Bytes(f.bytes.begin(), f.bytes.end())});
    times.push_back(at);
  }
  std::vector<Seen> frames;
  std::vector<TimePoint> times;
};

BusConfig config() {
  BusConfig c;
  c.name = "line";
  c.baud = 9600;
  return c;
}

TEST(FrameTap, SeesFramesNotChunksWithTheStationsVerdict) {
  PollStation st;
  Clock1 clock;
  Line1 line;
  BusEngine engine(config(), {&st}, clock, line, std::make_shared<spdlog::logger>("bus"));
  Recorder tap;
  engine.add_tap(&tap);
  engine.start();
  st.arm();
  engine.line_up(false);
  ASSERT_EQ(line.sent.size(), 1u);
  ASSERT_EQ(tap.frames.size(), 1u);
  EXPECT_EQ(tap.frames[0].direction, FrameDirection::to_drive);
  EXPECT_EQ(tap.frames[0].station, &st);
  EXPECT_EQ(tap.frames[0].bytes, (Bytes{0xA0, 0x01}));
  EXPECT_EQ(tap.times[0], clock.now_);
  engine.on_sent();
  clock.now_ += std::chrono::milliseconds(10);  // the request has left the wire
  // A damaged reply in two chunks: one frame, flagged; then the resend, flagged as such.
  const Bytes bad1 = {0xBE};
  const Bytes bad2 = {0x01, 0x00};
  engine.on_received(bad1);
  EXPECT_EQ(tap.frames.size(), 1u);
  engine.on_received(bad2);
  ASSERT_EQ(tap.frames.size(), 3u);
  EXPECT_EQ(tap.frames[1].direction, FrameDirection::from_drive);
  EXPECT_EQ(tap.frames[1].flags, frame_flags::bad_checksum);
  EXPECT_EQ(tap.frames[1].bytes, (Bytes{0xBE, 0x01, 0x00}));
  EXPECT_EQ(tap.frames[2].direction, FrameDirection::to_drive);
  EXPECT_EQ(tap.frames[2].flags, frame_flags::retry);
  engine.on_sent();
  clock.now_ += std::chrono::milliseconds(10);
  const Bytes good = {0xB0, 0x01, 0x07};
  engine.on_received(good);
  ASSERT_EQ(tap.frames.size(), 4u);
  EXPECT_EQ(tap.frames[3].flags, 0);
  EXPECT_EQ(tap.frames[3].bytes, good);
  // Outside any exchange on a polled line: noise, nobody's.
  const Bytes stray = {0x55, 0x66};
  engine.on_received(stray);
  ASSERT_EQ(tap.frames.size(), 5u);
  EXPECT_EQ(tap.frames[4].flags, frame_flags::noise);
  EXPECT_EQ(tap.frames[4].station, nullptr);
  // Removed: nothing more.
  engine.remove_tap(&tap);
  engine.on_received(stray);
  EXPECT_EQ(tap.frames.size(), 5u);
}

}  // namespace
}  // namespace drivegate
