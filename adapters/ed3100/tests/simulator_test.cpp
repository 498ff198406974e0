// The simulator answers as the document's examples do (vendor document, "Appendix ED3100"), and
// its operator commands. Made by the plugin's own factory, as `drivegate sim` makes it.
#include <gtest/gtest.h>

#include "drivegate/crc.h"

#include <memory>

#include "adapter_factories.h"
#include "adapter_under_test.h"
#include "codec.h"
#include "registers.h"

namespace drivegate::ed3100 {
namespace {

using B = Bytes;
const TimePoint kT0 = TimePoint{} + std::chrono::hours(1);

class SimTest : public ::testing::Test {
 protected:
  Bytes send(const Bytes& frame) { return sim.on_receive(frame, now); }
  void tick_for(Millis span) {
    for (const TimePoint end = now + span; now < end;) {
      now += Millis(10);
      sim.on_tick(now);
    }
  }
  std::vector<std::uint16_t> read_words(std::uint16_t reg, std::uint16_t count) {
    const Bytes r = send(encode_read(0x1F, reg, count));
    const auto d = decode_reply(
        r, {kFnRead, reg, static_cast<std::uint16_t>(reg >= kRegMonitorFirst ? 2 : count)});
    EXPECT_EQ(d.status, DecodeStatus::frame);
    return d.frame.words;
  }

  std::unique_ptr<Simulator> owned = test::make_simulator(drivegate_adapter, 0x1F);
  Simulator& sim = *owned;
  TimePoint now = kT0;
};

TEST_F(SimTest, DefaultsAnswerTheDocumentExamples) {
  // "03H: read register content".
  EXPECT_EQ(send({0x1F, 0x03, 0x00, 0x06, 0x00, 0x01, 0x67, 0xB5}),
            (B{0x1F, 0x03, 0x00, 0x06, 0x10, 0x88, 0xAB, 0xD3}));
  // "read monitoring parameters": 42.28 Hz, stopped.
  EXPECT_EQ(send({0x1F, 0x03, 0x0D, 0x00, 0x00, 0x00, 0x44, 0xD8}),
            (B{0x1F, 0x03, 0x0D, 0x00, 0x10, 0x84, 0x41, 0x48, 0x47, 0xD5}));
  // "Read fault code".
  EXPECT_EQ(send({0x1F, 0x03, 0x0E, 0x01, 0x00, 0x00, 0x15, 0x5C}),
            (B{0x1F, 0x03, 0x0E, 0x01, 0xFF, 0xFF, 0x01, 0x48, 0x0F, 0x2B}));
}

TEST_F(SimTest, WritesAnswerTheDocumentExamples) {
  // "06H": the response is the request.
  const B w06 = {0x1F, 0x06, 0x00, 0x06, 0x13, 0x88, 0x67, 0x23};
  EXPECT_EQ(send(w06), w06);
  EXPECT_EQ(read_words(0x0006, 1), std::vector<std::uint16_t>{0x1388});
  // "10H": 00-06 = 50.00, 00-07 = 00.01.
  EXPECT_EQ(send({0x1F, 0x10, 0x00, 0x06, 0x00, 0x02, 0x04, 0x13, 0x88, 0x00, 0x01, 0x56, 0xC3}),
            (B{0x1F, 0x10, 0x00, 0x06, 0x00, 0x02, 0xA2, 0x77}));
  EXPECT_EQ(read_words(0x0006, 2), (std::vector<std::uint16_t>{0x1388, 0x0001}));
  // "Written stop order".
  const B stop = {0x1F, 0x06, 0x20, 0x00, 0x00, 0x01, 0x40, 0x74};
  EXPECT_EQ(send(stop), stop);
}

TEST_F(SimTest, RunsForwardThenReverse) {
  // "Start forward command ... (continuous operation)" and its response.
  EXPECT_EQ(send({0x1F, 0x10, 0x20, 0x00, 0x00, 0x02, 0x04, 0x00, 0x1E, 0x10, 0x88, 0x67, 0xE6}),
            (B{0x1F, 0x10, 0x20, 0x00, 0x00, 0x02, 0x49, 0xB6}));
  tick_for(Millis(200));
  auto st = read_words(kRegFault, 0);
  EXPECT_TRUE(bit(st[1], kStRunning));
  EXPECT_TRUE(bit(st[1], kStAccelerating));
  EXPECT_FALSE(bit(st[1], kStCmdReverse));
  tick_for(Millis(1000));
  EXPECT_EQ(read_words(0x0D00, 0), (std::vector<std::uint16_t>{0x1088, 0x0148}));  // not stopped
  // "Reverse run command": passes through 0 Hz, then runs reverse.
  EXPECT_EQ(send({0x1F, 0x10, 0x20, 0x00, 0x00, 0x02, 0x04, 0x00, 0x2E, 0x10, 0x88, 0x67, 0xE9}),
            (B{0x1F, 0x10, 0x20, 0x00, 0x00, 0x02, 0x49, 0xB6}));
  tick_for(Millis(200));
  st = read_words(kRegFault, 0);
  EXPECT_TRUE(bit(st[1], kStDecelerating));
  EXPECT_FALSE(bit(st[1], kStRunReverse));
  EXPECT_TRUE(bit(st[1], kStCmdReverse));
  tick_for(Millis(2500));
  st = read_words(kRegFault, 0);
  EXPECT_TRUE(bit(st[1], kStRunReverse));
  EXPECT_TRUE(bit(st[1], kStRunning));
  // Stop: ramps down, then reports stopped and shows the reference.
  send({0x1F, 0x06, 0x20, 0x00, 0x00, 0x01, 0x40, 0x74});
  tick_for(Millis(1500));
  st = read_words(kRegFault, 0);
  EXPECT_FALSE(bit(st[1], kStRunning));
  EXPECT_EQ(read_words(0x0D00, 0), (std::vector<std::uint16_t>{0x1088, 0x4148}));
}

TEST_F(SimTest, BuffersChunksAndIgnoresOtherAddressesAndBadFrames) {
  const B req = {0x1F, 0x03, 0x00, 0x06, 0x00, 0x01, 0x67, 0xB5};
  for (std::size_t i = 0; i + 1 < req.size(); ++i)
    EXPECT_TRUE(sim.on_receive({&req[i], 1}, now).empty());
  EXPECT_EQ(sim.on_receive({&req.back(), 1}, now).size(), 8u);
  EXPECT_TRUE(send(encode_read(0x05, 0x0006, 1)).empty());
  B bad = req;
  bad[7] ^= 1;
  EXPECT_TRUE(send(bad).empty());
  EXPECT_EQ(send(req).size(), 8u);  // and recovers
}

TEST_F(SimTest, BroadcastIsAppliedWithoutReply) {
  EXPECT_TRUE(send(encode_write_single(0x00, 0x0006, 0x1234)).empty());
  EXPECT_EQ(read_words(0x0006, 1), std::vector<std::uint16_t>{0x1234});
}

TEST_F(SimTest, StandardForm) {
  EXPECT_EQ(sim.control("form standard", now), "ok form=standard");
  EXPECT_EQ(send({0x1F, 0x03, 0x0D, 0x00, 0x00, 0x00, 0x44, 0xD8}),
            (B{0x1F, 0x03, 0x04, 0x10, 0x84, 0x41, 0x48, 0x70, 0xBD}));
  sim.control("param 00-06 0x1388", now);
  // shared/specs/README.md "ed3100": the standard form example.
  EXPECT_EQ(send({0x1F, 0x03, 0x00, 0x06, 0x00, 0x01, 0x67, 0xB5}),
            (B{0x1F, 0x03, 0x02, 0x13, 0x88, 0x1D, 0x10}));
}

TEST_F(SimTest, Exceptions) {
  // Beyond 0x0D28 (document: "reading invalid address more than 0D28").
  EXPECT_EQ(send(encode_read(0x1F, 0x0D29, 0)), encode_exception(0x1F, 0x03, 0x02));
  // Function 10 writes at most two registers (document, "10H").
  Bytes three = {0x1F, 0x10, 0x00, 0x06, 0x00, 0x03, 0x06, 0, 1, 0, 2, 0, 3};
  append_crc16_modbus(three);
  EXPECT_EQ(send(three), encode_exception(0x1F, 0x10, 0x03));
  EXPECT_EQ(send(encode_write_single(0x1F, 0x2000, 0x0005)), encode_exception(0x1F, 0x06, 0x03));
  EXPECT_EQ(send(encode_write_single(0x1F, 0x0E01, 0x0005)), encode_exception(0x1F, 0x06, 0x02));
}

TEST_F(SimTest, FaultRefusesRunsUntilReset) {
  EXPECT_EQ(sim.control("fault 0x12", now), "ok fault=0x0012");
  auto st = read_words(kRegFault, 0);
  EXPECT_EQ(st[0], 0x0012);
  EXPECT_TRUE(bit(st[1], kStFault));
  EXPECT_EQ(send(encode_write_single(0x1F, 0x2000, kCmdForward)),
            encode_exception(0x1F, 0x06, 0x04));
  const B reset = encode_write_single(0x1F, kRegResetDefault, kResetValueDefault);
  EXPECT_EQ(send(reset), reset);
  EXPECT_EQ(read_words(kRegFault, 0)[0], kNoFault);
  sim.control("fault 7", now);
  EXPECT_EQ(sim.control("clear", now), "ok");
  EXPECT_EQ(read_words(kRegFault, 0)[0], kNoFault);
}

TEST_F(SimTest, SilenceAndCorruption) {
  const B req = {0x1F, 0x03, 0x00, 0x06, 0x00, 0x01, 0x67, 0xB5};
  sim.control("silent on", now);
  EXPECT_TRUE(send(req).empty());
  sim.control("silent off", now);
  sim.control("corrupt 2", now);
  for (int i = 0; i < 2; ++i) {
    const Bytes r = send(req);
    EXPECT_EQ(decode_reply(r, {kFnRead, 0x0006, 1}).error, FrameError::bad_checksum);
  }
  EXPECT_EQ(send(req), (B{0x1F, 0x03, 0x00, 0x06, 0x10, 0x88, 0xAB, 0xD3}));
}

TEST_F(SimTest, LockRefusesWritesButAnswersReads) {
  EXPECT_EQ(sim.control("lock on", now), "ok lock=on");
  EXPECT_EQ(send(encode_write_single(0x1F, 0x2000, kCmdStop)), encode_exception(0x1F, 0x06, 0x04));
  const std::uint16_t run[] = {kCmdForward, 0x1388};
  EXPECT_EQ(send(encode_write_multiple(0x1F, 0x2000, run)), encode_exception(0x1F, 0x10, 0x04));
  EXPECT_EQ(send(encode_write_single(0x1F, 0x0006, 0x1234)), encode_exception(0x1F, 0x06, 0x04));
  EXPECT_EQ(read_words(0x0006, 1), std::vector<std::uint16_t>{0x1088});  // nothing stored
  EXPECT_EQ(read_words(kRegFault, 0), (std::vector<std::uint16_t>{0xFFFF, 0x0148}));
  EXPECT_EQ(sim.control("lock off", now), "ok lock=off");
  const Bytes w = encode_write_single(0x1F, 0x0006, 0x1234);
  EXPECT_EQ(send(w), w);
}

TEST_F(SimTest, ControlStateAndErrors) {
  const std::string s = sim.control("state", now);
  for (const char* key : {"address=31", "form=document", "command=0x0001", "reference=0x1084",
                          "running=0", "fault=0xFFFF", "state=0x0148", "param_00_06=0x1088"}) {
    EXPECT_NE(s.find(key), std::string::npos) << key << " in " << s;
  }
  EXPECT_EQ(sim.control("bogus", now).rfind("error:", 0), 0u);
  EXPECT_NE(sim.control("help", now).find("lock on|off"), std::string::npos);
  EXPECT_EQ(sim.control("help", now).rfind("error:", 0), std::string::npos);
  EXPECT_EQ(sim.control("fault", now).rfind("error:", 0), 0u);
  EXPECT_EQ(sim.control("monitor 0D05 123 0x0104", now), "ok");
  EXPECT_EQ(read_words(0x0D05, 0), (std::vector<std::uint16_t>{123, 0x0104}));
}

}  // namespace
}  // namespace drivegate::ed3100
