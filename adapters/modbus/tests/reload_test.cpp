// A reload while a command's sequence is on the line (ABB Drives' 0x047E then 0x047F): the real
// modbus driver in devices the gateway builds and replaces, driven through their Station calls
// (as the bus engine calls them) on a time the test sets, the slave's echoes given by hand
// (support::ReloadRig).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "reload_support.h"

namespace drivegate::modbus_device::modbus_reload_test {
namespace {

using namespace std::chrono_literals;
using ::testing::ElementsAre;

constexpr std::uint8_t kSlave = 7;

// The drive in Hz (support::kHzProfile) with ABB Drives-like commands: a run passes through
// 0x047E (ready to operate) before 0x047F (operating); the stop is 0x047E.
const std::string kProfile = support::replaced(
    support::replaced(support::kHzProfile, "name = \"hz-drive\"", "name = \"seq-drive\""),
    "stop = { point = \"control_word\", sequence = [0x0007, 0x0006] }\n"
    "run_forward = { point = \"control_word\", sequence = [0x0006, 0x0007, 0x000F] }\n",
    "stop = { point = \"control_word\", value = 0x047E }\n"
    "run_forward = { point = \"control_word\", sequence = [0x047E, 0x047F] }\n");

Bytes fc06(std::uint16_t address, std::uint16_t value) {
  return support::fc06_frame(kSlave, address, value);
}

class ReloadMidSequence : public support::ReloadRig {
 protected:
  ReloadMidSequence() : ReloadRig(kProfile, "seq.toml") {}

  [[nodiscard]] Config config(double poles) const {
    DeviceConfig d = device("drive", kSlave);
    d.options.set("motor_poles", poles);
    return ReloadRig::config(d);
  }

  // Every poll the device sends until it is online is answered: control word 0x047E, reference
  // 0, status 0 (stopped); each frame sent is kept in sent_.
  void bring_online(Device& d, Millis ms) {
    for (int i = 0; i < 10 && !d.online(); ++i) {
      auto ex = d.next_exchange(at(ms), Turn::poll);
      if (!ex) {
        d.on_tick(at(ms));
        continue;
      }
      sent_.push_back(ex->frame);
      ASSERT_EQ(ex->frame[1], 0x03);
      const std::uint16_t start = static_cast<std::uint16_t>(ex->frame[2] << 8 | ex->frame[3]);
      const std::uint16_t count = static_cast<std::uint16_t>(ex->frame[4] << 8 | ex->frame[5]);
      std::vector<std::uint16_t> words(count, 0);
      if (start == 0 && count > 0) words[0] = 0x047E;
      d.link().health.frame_good(at(ms));
      d.on_receive(encode(Framing::rtu, kSlave, support::words_pdu(0x03, words)), at(ms));
      d.link().health.data_good(at(ms), at(ms));
      d.on_tick(at(ms));
    }
    ASSERT_TRUE(d.online());
  }
  // The device's next write on the line, echoed by the slave; nullopt when it has none.
  std::optional<Bytes> step(Device& d, Millis ms) {
    auto ex = d.next_exchange(at(ms), Turn::write);
    if (!ex) return std::nullopt;
    sent_.push_back(ex->frame);
    if (ex->frame[1] == 0x06) {
      d.on_receive(ex->frame, at(ms));  // the echo: confirmed
    } else {
      d.on_no_reply(at(ms));
    }
    d.on_tick(at(ms));
    return ex->frame;
  }
  // The writes (FC 06) sent from `from` on.
  std::vector<Bytes> writes_from(std::size_t from) const {
    std::vector<Bytes> out;
    for (std::size_t i = from; i < sent_.size(); ++i) {
      if (sent_[i][1] == 0x06) out.push_back(sent_[i]);
    }
    return out;
  }
};

// The profile changed (an option): the held device lets its writes in flight settle
// (Gateway::hold_for_reload), and a sequence on the line is one write, as docs/profiles.md
// ("Sequences") says: its second step goes during the hold and the run is answered ok, once, as a
// single write in flight would be. Cutting it after its first step would leave the client's
// command neither done nor refused by the drive. The new device starts from what it reads and
// sends no step of the old sequence again.
TEST_F(ReloadMidSequence, AChangedDeviceFinishesTheSequenceOnTheLineDuringTheHold) {
  auto old = build(config(4));
  Device& d = *old->find("drive");
  bring_online(d, 0ms);
  std::vector<Outcome> answers;
  const std::uint16_t run = 1;  // run_forward
  ASSERT_EQ(d.write(
                kPlc, Table::holding, 0, std::span(&run, 1),
                [&](Outcome o) { answers.push_back(o); }, at(10ms)),
            Outcome::ok);
  const std::size_t mark = sent_.size();
  ASSERT_EQ(step(d, 10ms), fc06(0, 0x047E));  // the first step, confirmed
  EXPECT_TRUE(answers.empty());

  auto next = build(config(2));                       // motor_poles 4 -> 2: the device changed
  EXPECT_GT(old->hold_for_reload(*next), Millis(0));  // held: a write in flight
  EXPECT_EQ(old->held_writes(), 1u);
  for (int i = 0; i < 5 && old->held_writes() > 0; ++i) step(d, Millis(20 + 10 * i));
  EXPECT_EQ(old->held_writes(), 0u);
  EXPECT_THAT(answers, ElementsAre(Outcome::ok));
  EXPECT_THAT(writes_from(mark), ElementsAre(fc06(0, 0x047E), fc06(0, 0x047F)));

  next->adopt(*old);
  old->stop();
  Device& fresh = *next->find("drive");
  EXPECT_NE(&fresh, &d);
  const std::size_t after = sent_.size();
  bring_online(fresh, 100ms);
  for (int i = 0; i < 5; ++i) step(fresh, Millis(110 + 10 * i));
  EXPECT_THAT(writes_from(after), ::testing::IsEmpty());
  EXPECT_THAT(answers, ElementsAre(Outcome::ok));  // answered once, never again
}

// The profile unchanged: the device moves to the new gateway as it runs, and its sequence runs on
// to its end: the run is confirmed.
TEST_F(ReloadMidSequence, AnUnchangedDeviceRunsItsSequenceOn) {
  auto old = build(config(4));
  Device& d = *old->find("drive");
  bring_online(d, 0ms);
  std::vector<Outcome> answers;
  const std::uint16_t run = 1;
  ASSERT_EQ(d.write(
                kPlc, Table::holding, 0, std::span(&run, 1),
                [&](Outcome o) { answers.push_back(o); }, at(10ms)),
            Outcome::ok);
  const std::size_t mark = sent_.size();
  ASSERT_EQ(step(d, 10ms), fc06(0, 0x047E));
  auto next = build(config(4));
  EXPECT_EQ(old->hold_for_reload(*next), Millis(0));  // kept: nothing to wait for
  next->adopt(*old);
  old->stop();
  EXPECT_EQ(next->find("drive"), &d);
  EXPECT_EQ(step(d, 20ms), fc06(0, 0x047F));
  EXPECT_THAT(answers, ElementsAre(Outcome::ok));
  EXPECT_THAT(writes_from(mark), ElementsAre(fc06(0, 0x047E), fc06(0, 0x047F)));
}

}  // namespace
}  // namespace drivegate::modbus_device::modbus_reload_test
