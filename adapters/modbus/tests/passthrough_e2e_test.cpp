// Pass-through windows under attack, end to end: the real daemon, `drivegate sim` on two lines,
// and clients of the lowest access level sending what a hostile one would (docs/profiles.md,
// "Pass-through").
//
// Line "drives" carries a native ED3100 (unit 1, address 1: its own adapter and simulator, which
// records every byte it hears) and a pass-through window onto address 2, where nobody answers;
// line "meters" a window (unit 3) onto a profile slave, `drivegate sim modbus`. A read-only TCP
// client and a read-only ASCII serial master (pymodbus's, on a serial listener) send FC 08 0000
// whose data is two ED3100 writes, FC 03 with a write behind its CRC, and FC 14 with a write
// inside its sub-requests: both simulators find frame ends by function length, and would run
// their motors. Each is refused with exception 03 and audited; no byte of the writes reaches
// either line; the ED3100 stays stopped, the PLC reads it stopped, and so does the profile slave.
//
// And the queue shared fairly: eight read connections keeping 4 reads each in flight against
// the meters window never get a maintain client's write refused busy.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sstream>
#include <thread>

#include "e2e.h"
#include "modbus_flood.h"
#include "pymodbus_slave.h"  // have_pymodbus_tools
#include "rtu_frames.h"
#include "serial_master.h"

namespace drivegate::test {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;
using Pdu = std::vector<std::uint8_t>;

bool have_adapter(const std::string& id) {
  return std::filesystem::exists(plugin_dir() / ("drivegate-" + id + ".so"));
}

std::string config(const std::filesystem::path& dir, int read_port) {
  return maintain_and_read_listeners(read_port) + "[[listener]]\nport = \"" + (dir / "s").string() +
         "\"\nbaud = 19200\nframing = \"ascii\"\ndata_bits = 8\naccess = \"read\"\n\n"
         "[[bus]]\nname = \"drives\"\nport = \"" +
         (dir / "ed").string() +
         "\"\nbaud = 9600\nparity = \"even\"\ndata_bits = 8\nstop_bits = 1\n\n"
         "[[device]]\nname = \"ed\"\nbus = \"drives\"\nadapter = \"ed3100\"\nunit_id = 1\n"
         "address = 1\n\n"
         "[[device]]\nname = \"window\"\nbus = \"drives\"\nadapter = \"modbus\"\nunit_id = 2\n"
         "address = 2\n[device.options]\npassthrough = true\ncomm_timeout_ms = 600000\n\n"
         "[[bus]]\nname = \"meters\"\nport = \"" +
         (dir / "mb").string() +
         "\"\nbaud = 19200\nparity = \"even\"\n\n"
         "[[device]]\nname = \"meter\"\nbus = \"meters\"\nadapter = \"modbus\"\nunit_id = 3\n"
         "address = 3\n[device.options]\npassthrough = true\n"
         // A simulator under a sanitizer on a loaded machine can start its reply later than the
         // default 100 ms: a write then ends 0x0B, which is not what the queue's test is about.
         "timeout_ms = 1000\n";
}

std::string hex(const Pdu& bytes) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  for (const std::uint8_t b : bytes) {
    out += kHex[b >> 4];
    out += kHex[b & 0xF];
  }
  return out;
}

// The ED3100 at 1 (document: 0x2001 frequency, 0x2000 command): 40.00 Hz, run forward.
const Pdu kSpeed = with_crc({0x01, 0x06, 0x20, 0x01, 0x0F, 0xA0});
const Pdu kRun = with_crc({0x01, 0x06, 0x20, 0x00, 0x00, 0x1E});
// The profile slave at 3 (example-vfd): control word (holding 0) := run_forward.
const Pdu kMeterRun = with_crc({0x03, 0x06, 0x00, 0x00, 0x00, 0x0F});

// FC 08 return query data whose data is the two ED3100 writes.
Pdu query_carrying_writes() {
  return joined({{0x08, 0x00, 0x00}, kSpeed, kRun});
}
// FC 03 to `address`, the CRC a slave checks after its 8 bytes, then `write`.
Pdu read_then(std::uint8_t address, const Pdu& write) {
  const Pdu read = {0x03, 0x00, 0x64, 0x00, 0x01};
  const Pdu frame = with_crc(joined({{address}, read}));
  return joined({read, Pdu(frame.end() - 2, frame.end()), write});
}
// FC 14 (read file record) of three well-formed sub-requests, the third starting the run at the
// ED3100's address: its simulator skips 0x14 byte by byte and lands on it.
Pdu file_record_carrying_run() {
  return joined({{0x14, 0x15, 0x06, 0, 0, 0, 0, 0, 0x01, 0x06, 0, 0, 0, 0, 0, 0x01},
                 Pdu(kRun.begin() + 1, kRun.end())});
}

class PassthroughE2E : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!have_adapter("ed3100")) GTEST_SKIP() << "ed3100 is not built";
    if (!have_pymodbus_tools()) GTEST_SKIP() << "socat and python3-pymodbus: tools/deps.sh test";
    line_ = std::make_unique<PtyPair>(dir_ / "m", dir_ / "s", dir_ / "socat.err");
    ed_ = std::make_unique<Sim>(
        "ed3100", dir_ / "ed",
        std::vector<std::string>{"--address", "1", "--wire-timing", "--wire-log",
                                 (dir_ / "ed-wire.log").string()});
    meter_ = std::make_unique<Sim>(
        "modbus", dir_ / "mb",
        std::vector<std::string>{"--address", "3", "--set", "profile=example-vfd"});
    daemon_ = std::make_unique<Daemon>(dir_, config(dir_.path(), read_port_),
                                       std::vector<std::string>{}, dir_ / "daemon.log");
    plc_ = std::make_unique<Plc>(daemon_->port(), 1);
    ASSERT_TRUE(plc_->connect());
    ASSERT_TRUE(comes_online(*plc_)) << log();
    // The meters window answers (the profile slave's status word, holding 100).
    ASSERT_TRUE(eventually(
        [&] {
          return raw_request(read_port_, 3, {0x03, 0x00, 0x64, 0x00, 0x01}).size() == 4;
        },
        10s))
        << log();
  }
  std::string log() { return slurp(dir_ / "daemon.log"); }
  // The read-only ASCII master's steps; one line of output each.
  std::vector<std::string> ascii_master(const std::vector<std::string>& steps) {
    // Each reply awaited to its CR LF (up to 5 s): under a sanitizer on a loaded machine a refusal
    // can take longer than the master's usual window, and must not be read as silence.
    return run_serial_master(
        {"--port", (dir_ / "m").string(), "--framing", "ascii", "--ascii-wait", "5000"}, steps,
        dir_ / "master.err");
  }

  TempDir dir_;
  int read_port_ = free_port();
  std::unique_ptr<PtyPair> line_;
  std::unique_ptr<Sim> ed_;
  std::unique_ptr<Sim> meter_;
  std::unique_ptr<Daemon> daemon_;
  std::unique_ptr<Plc> plc_;
};

TEST_F(PassthroughE2E, NoReadOnlyClientSmugglesAWriteOntoALine) {
  const Pdu query = query_carrying_writes();
  const Pdu trailing = read_then(2, kRun);
  const Pdu file = file_record_carrying_run();
  const Pdu meter_trailing = read_then(3, kMeterRun);

  // The read-only TCP client: exception 03 for each, at once.
  EXPECT_EQ(raw_request(read_port_, 2, query), (Pdu{0x88, 0x03}));
  EXPECT_EQ(raw_request(read_port_, 2, trailing), (Pdu{0x83, 0x03}));
  EXPECT_EQ(raw_request(read_port_, 2, file), (Pdu{0x94, 0x03}));
  EXPECT_EQ(raw_request(read_port_, 3, meter_trailing), (Pdu{0x83, 0x03}));
  // The read-only ASCII serial master: the same, in ASCII (':', unit 02, function | 0x80, 03).
  const auto out = ascii_master({"ascii", "2", hex(query), "ascii", "2", hex(trailing), "ascii",
                                 "2", hex(file), "ascii", "3", hex(meter_trailing)});
  ASSERT_EQ(out.size(), 4u) << ::testing::PrintToString(out) << slurp(dir_ / "master.err");
  for (const auto& [line, head] :
       {std::pair{out[0], std::string(":028803")}, std::pair{out[1], std::string(":028303")},
        std::pair{out[2], std::string(":029403")}, std::pair{out[3], std::string(":038303")}}) {
    EXPECT_EQ(line.rfind("reply " + hex(Pdu(head.begin(), head.end())), 0), 0u) << line;
  }

  // The ED3100 would ramp within this; it never heard a run, and stands still.
  std::this_thread::sleep_for(1500ms);
  EXPECT_THAT(ed_->control("state"), HasSubstr(" running=0 "));
  EXPECT_EQ(plc_->holding(reg::command, 1).regs[0], 0);
  EXPECT_EQ(plc_->input(reg::status, 1).regs[0] & reg::running, 0);
  EXPECT_THAT(meter_->control("state"), HasSubstr(" stopped"));
  // Every byte the ED3100's line carried: none of the writes.
  ed_->process().stop();  // SIGTERM: it writes out its wire log
  std::string heard;
  std::istringstream wire(slurp(dir_ / "ed-wire.log"));
  for (std::string kind, a, b, n, bytes; wire >> kind;) {
    if (kind != "rx") {
      std::getline(wire, a);
      continue;
    }
    wire >> a >> b >> n >> bytes;
    heard += bytes;
  }
  EXPECT_THAT(heard, HasSubstr("0103"));  // its own polls reached it
  EXPECT_EQ(heard.find(hex(kRun)), std::string::npos);
  EXPECT_EQ(heard.find(hex(kSpeed)), std::string::npos);

  // The audit trail: each refusal with its reason, from both kinds of client.
  const std::string text = log();
  EXPECT_GE(occurrences(text, "(function 0x08: 19 bytes where its length is 5)"), 2u) << text;
  EXPECT_GE(occurrences(text, "(a whole request inside it, at byte 16 of its frame)"), 2u) << text;
  EXPECT_GE(occurrences(text, "invalid value (function 0x03: 15 bytes where its length is 5)"), 4u)
      << text;
  EXPECT_THAT(text, HasSubstr("write to window (unit 2) from modbus_serial"));
  EXPECT_THAT(text, HasSubstr("write to meter (unit 3) from modbus 127.0.0.1:"));

  // Whole requests still go through: a read of the profile slave's status word.
  const Pdu status = raw_request(read_port_, 3, {0x03, 0x00, 0x64, 0x00, 0x01});
  ASSERT_EQ(status.size(), 4u);
  EXPECT_EQ(Pdu(status.begin(), status.begin() + 2), (Pdu{0x03, 0x02}));
}

TEST_F(PassthroughE2E, ReadClientsFillingAWindowsQueueNeverLockAMaintainWriteOut) {
  std::vector<std::unique_ptr<Flood>> readers;
  for (int i = 0; i < 8; ++i) {
    readers.push_back(std::make_unique<Flood>(read_port_, 3, 4));
    ASSERT_TRUE(readers.back()->connected());
  }
  std::vector<std::thread> threads;
  for (auto& r : readers) {
    threads.emplace_back([flood = r.get()] {
      flood->run(4s, [](std::uint64_t) { return Pdu{0x03, 0x00, 0x64, 0x00, 0x01}; });
    });
  }
  std::this_thread::sleep_for(500ms);  // the queue is full of reads
  std::vector<Pdu> answers;
  for (std::uint16_t value = 1000; value < 1010; ++value) {
    // FC 06: the example profile's speed_reference (holding 1).
    const Pdu write = {0x06, 0x00, 0x01, static_cast<std::uint8_t>(value >> 8),
                       static_cast<std::uint8_t>(value)};
    answers.push_back(raw_request(daemon_->port(), 3, write));
    EXPECT_EQ(answers.back(), write) << "a maintain write was not taken beside the reads";
    std::this_thread::sleep_for(200ms);
  }
  for (auto& t : threads) t.join();
  std::size_t reads_answered = 0;
  for (const auto& r : readers) reads_answered += r->count(0);
  EXPECT_GT(reads_answered, 50u);  // the reads were served all along
  // The slave holds the last value written: 1009.
  EXPECT_EQ(raw_request(daemon_->port(), 3, {0x03, 0x00, 0x01, 0x00, 0x01}),
            (Pdu{0x03, 0x02, 0x03, 0xF1}));
}

}  // namespace
}  // namespace drivegate::test
