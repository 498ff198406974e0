// What `drivegate scan` prints (cli/scan_report.h, cli/scan_progress.h), and the profile key it
// suggests profiles by ([profile] identification, adapters/modbus/profile.h).
#include "scan_report.h"

#include <gtest/gtest.h>

#include <sstream>

#include "codec.h"
#include "profile.h"
#include "scan.h"
#include "scan_progress.h"

namespace drivegate::cli {
namespace {

using namespace std::chrono_literals;
namespace md = modbus_device;

// Slave 17's replies as pymodbus frames them (tests/cli/scan_test.cpp says where from): holding
// 0 = 6, and the Toshiba VF-S15 manual's identification; slave 18 answers exception 02 and
// refuses identification with 01.
const Bytes kRegisters17 = {0x11, 0x03, 0x02, 0x00, 0x06, 0xF9, 0x85};
const Bytes kToshiba17 = {0x11, 0x2B, 0x0E, 0x01, 0x02, 0x00, 0x00, 0x03, 0x00, 0x07, 'T', 'O',
                          'S',  'H',  'I',  'B',  'A',  0x01, 0x07, 'P',  'N',  'E',  '0', '0',
                          '1',  'Z',  0x02, 0x04, '0',  '2',  '0',  '1',  0x5B, 0x95};

// Addresses 16..18 probed: 16 silent, 17 a Toshiba, 18 without identification.
md::Scanner scanned() {
  md::ScanSettings s;
  s.char_time = character_time(19200, Parity::even, 8, 1);
  std::string error;
  s.addresses = *md::parse_addresses("16-18", error);
  md::Scanner scan(s);
  scan.next();
  scan.on_timeout();
  scan.next();
  scan.on_receive(kRegisters17);
  scan.next();
  scan.on_receive(kToshiba17);
  scan.next();
  scan.on_receive(md::encode(md::Framing::rtu, 18, md::exception_pdu(0x03, 0x02)));
  scan.next();
  scan.on_receive(md::encode(md::Framing::rtu, 18, md::exception_pdu(0x2B, 0x01)));
  EXPECT_FALSE(scan.next());
  return scan;
}

BusConfig tty() {
  BusConfig line;
  line.port = "/dev/ttyUSB0";
  line.baud = 19200;
  line.parity = Parity::even;
  return line;
}

const std::vector<KnownProfile> kProfiles = {
    {"tosvert-vf-s15", {"Toshiba", "PNE001Z"}},
    {"/home/me/profiles/acme.toml", {"ACME", "X*"}},
};

TEST(ScanReport, ALinePerSlaveTheSummaryAndTheConfigurationForThem) {
  const md::Scanner scan = scanned();
  ScanReport r;
  r.line = tty();
  r.addresses = "16-18";
  r.scanner = &scan;
  r.profiles = kProfiles;
  EXPECT_EQ(scan_report(r),
            "address 17: holding register 0 = 6; VendorName \"TOSHIBA\", ProductCode \"PNE001Z\", "
            "MajorMinorRevision \"0201\"; profile tosvert-vf-s15\n"
            "address 18: exception 02 (illegal data address) to a read of holding register 0; no "
            "identification: exception 01 (illegal function); no profile suggested without "
            "VendorName and ProductCode\n"
            "2 slaves found on /dev/ttyUSB0 (19200 baud 8E1, rtu), addresses 16-18\n"
            "\n"
            "# drivegate.toml for what was found (docs/profiles.md); each unit_id is the slave's "
            "address\n"
            "[[bus]]\n"
            "name = \"ttyUSB0\"\n"
            "port = \"/dev/ttyUSB0\"\n"
            "baud = 19200\n"
            "parity = \"even\"\n"
            "data_bits = 8\n"
            "stop_bits = 1\n"
            "\n"
            "[[device]]\n"
            "name = \"ttyUSB0-17\"\n"
            "bus = \"ttyUSB0\"\n"
            "adapter = \"modbus\"\n"
            "unit_id = 17\n"
            "address = 17\n"
            "[device.options]\n"
            "profile = \"tosvert-vf-s15\"\n"
            "\n"
            "[[device]]\n"
            "name = \"ttyUSB0-18\"\n"
            "bus = \"ttyUSB0\"\n"
            "adapter = \"modbus\"\n"
            "unit_id = 18\n"
            "address = 18\n"
            "[device.options]\n"
            "# no profile matches it: write one (docs/profiles.md) and name it here\n"
            "profile = \"/etc/drivegate/profiles/slave-18.toml\"\n");
}

TEST(ScanReport, AProfileIsSuggestedOnlyWhenItsIdentificationMatches) {
  const md::Scanner scan = scanned();
  const md::FoundSlave& toshiba = scan.found()[0];
  ASSERT_EQ(toshiba.address, 17);
  EXPECT_EQ(matching_profiles(toshiba, kProfiles).size(), 1u);
  const std::vector<KnownProfile> others = {{"tosvert-vf-s11", {"Toshiba", "PNE002*"}}};
  EXPECT_TRUE(matching_profiles(toshiba, others).empty());
  EXPECT_EQ(slave_line(toshiba, others),
            "address 17: holding register 0 = 6; VendorName \"TOSHIBA\", ProductCode \"PNE001Z\", "
            "MajorMinorRevision \"0201\"; no profile matches\n");
  // Two that match: both named, the first in the snippet.
  const std::vector<KnownProfile> two = {{"a", {"toshiba", "PNE*"}}, {"b", {"TOSHIBA", "PNE001Z"}}};
  EXPECT_NE(slave_line(toshiba, two).find("; profiles a, b\n"), std::string::npos);
}

TEST(ScanReport, NothingFoundIsSaidWithoutAConfiguration) {
  md::ScanSettings s;
  s.char_time = character_time(9600, Parity::none, 8, 1);
  s.addresses = {1, 2};
  s.framing = md::Framing::ascii;
  md::Scanner scan(s);
  scan.next();
  // Bytes of another baud rate: they make no frame, twice.
  const Bytes noise = {0x3A, 0xF0, 0x0D, 0x0A};
  scan.on_receive(noise);
  scan.on_timeout();
  scan.next();
  scan.on_receive(noise);
  scan.on_timeout();
  scan.next();
  scan.on_timeout();
  ASSERT_TRUE(scan.next());  // the wait for a late reply to the last probe
  scan.on_timeout();
  EXPECT_FALSE(scan.next());
  ScanReport r;
  r.line = tty();
  r.line.baud = 9600;
  r.line.parity = Parity::none;
  r.line.stop_bits = 2;
  r.framing = md::Framing::ascii;
  r.addresses = "1,2";
  r.scanner = &scan;
  EXPECT_EQ(scan_report(r),
            "no slave found on /dev/ttyUSB0 (9600 baud 8N2, ascii), addresses 1,2\n"
            "note: bytes that made no good frame came at address 1: another baud rate, parity or "
            "framing on the line, two slaves at one address, or a reply cut short or whose byte "
            "count says more than it carries\n");
}

// A slave whose well-formed reply carries another byte count than a read of one register has is
// found, and its line says what it answered.
TEST(ScanReport, AReplyWithAnotherByteCountIsSaidOnTheSlavesLine) {
  md::ScanSettings s;
  s.char_time = character_time(19200, Parity::even, 8, 1);
  s.addresses = {17};
  md::Scanner scan(s);
  scan.next();
  ASSERT_TRUE(
      scan.on_receive(md::encode(md::Framing::rtu, 17, Bytes{0x03, 0x04, 0x00, 0x06, 0, 0})));
  EXPECT_EQ(slave_line(scan.found().at(0), {}).substr(0, 126),
            "address 17: a read of holding register 0 answered with byte count 4 and 4 bytes, not "
            "the 2 of one register; identification not");
}

TEST(ScanReport, ADevicesStringsCannotWriteToTheTerminal) {
  md::ScanSettings s;
  s.addresses = {1};
  md::Scanner scan(s);
  scan.next();
  scan.on_receive(md::encode(md::Framing::rtu, 1, Bytes{0x03, 0x02, 0x00, 0x00}));
  scan.next();
  const Bytes id = {0x2B, 0x0E, 0x01, 0x01, 0x00, 0x00, 0x02, 0x00, 0x04,
                    'A',  '"',  0x1B, '[',  0x01, 0x03, 'B',  '\\', 0xFF};
  scan.on_receive(md::encode(md::Framing::rtu, 1, id));
  EXPECT_EQ(slave_line(scan.found()[0], {}),
            "address 1: holding register 0 = 0; VendorName \"A\\\"\\x1B[\", ProductCode "
            "\"B\\\\\\xFF\"; no profile matches\n");
}

TEST(ScanReport, AnInterruptedScanSaysWhereItStopped) {
  md::ScanSettings s;
  s.addresses = {1, 2, 3};
  md::Scanner scan(s);
  scan.next();
  scan.on_timeout();
  ScanReport r;
  r.line = tty();
  r.addresses = "1-3";
  r.scanner = &scan;
  r.interrupted = true;
  EXPECT_EQ(scan_report(r),
            "no slave found on /dev/ttyUSB0 (19200 baud 8E1, rtu), addresses 1-3: interrupted "
            "after 1 of 3\n");
}

TEST(ScanProgress, AtMostOnceASecondALineOfItsOwnOutsideATerminal) {
  std::ostringstream out;
  ScanProgress p(out, false);
  const auto t0 = ScanProgress::Clock::time_point{} + 1h;
  p.start(t0, {0, 247, 0, 27911ms});
  p.tick(t0 + 999ms, {8, 247, 0, 27000ms});
  p.tick(t0 + 1000ms, {9, 247, 1, 26100ms});
  p.tick(t0 + 1500ms, {13, 247, 1, 25000ms});
  p.finish(t0 + 1600ms, {247, 247, 1, 0ms});
  EXPECT_EQ(out.str(),
            "drivegate scan: 0 of 247 addresses, 0 slaves found, at most 28 s left\n"
            "drivegate scan: 9 of 247 addresses, 1 slave found, at most 27 s left\n"
            "drivegate scan: 247 of 247 addresses, 1 slave found, at most 0 s left\n");
}

TEST(ScanProgress, InATerminalTheLineIsRedrawnInPlace) {
  std::ostringstream out;
  ScanProgress p(out, true);
  const auto t0 = ScanProgress::Clock::time_point{} + 1h;
  p.start(t0, {0, 2, 0, 300ms});
  p.finish(t0 + 200ms, {2, 2, 0, 0ms});
  EXPECT_EQ(out.str(),
            "\rdrivegate scan: 0 of 2 addresses, 0 slaves found, at most 1 s left\033[K"
            "\rdrivegate scan: 2 of 2 addresses, 0 slaves found, at most 0 s left\033[K\n");
}

// [profile] identification: what a slave's basic identification says when it is the device.
std::string profile_with(const std::string& identification) {
  return "[profile]\nname = \"tosvert\"\nsource = \"the manual\"\n" + identification +
         "\n[[point]]\nname = \"speed\"\ntable = \"input\"\naddress = 0\ntype = \"u16\"\n";
}

std::vector<std::string> errors_of(const std::string& text) {
  auto parsed = md::parse_profile(text, "t.toml");
  if (auto* e = std::get_if<std::vector<std::string>>(&parsed)) return *e;
  return {};
}

TEST(ProfileIdentification, AnInlineTableOrASubTable) {
  for (const std::string& form :
       {std::string("identification = { vendor_name = \"Toshiba\", product_code = \"PNE001Z\" }"),
        std::string("[profile.identification]\nvendor_name = \"Toshiba\"\n"
                    "product_code = \"PNE001Z\"")}) {
    auto parsed = md::parse_profile(profile_with(form), "t.toml");
    ASSERT_TRUE(std::holds_alternative<md::Profile>(parsed)) << errors_of(profile_with(form))[0];
    const auto& id = std::get<md::Profile>(parsed).identification;
    ASSERT_TRUE(id);
    EXPECT_EQ(id->vendor_name, "Toshiba");
    EXPECT_EQ(id->product_code, "PNE001Z");
  }
  auto none = md::parse_profile(profile_with(""), "t.toml");
  ASSERT_TRUE(std::holds_alternative<md::Profile>(none));
  EXPECT_FALSE(std::get<md::Profile>(none).identification);
}

TEST(ProfileIdentification, BothKeysNamingOneProduct) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"identification = { vendor_name = \"Toshiba\" }",
       "t.toml:4: profile.identification.product_code: required key is missing"},
      {"identification = { vendor_name = \"Toshiba\", product_code = \"*\" }",
       "t.toml:4: profile.identification.product_code: must name a product (a trailing '*' may "
       "stand for the rest of it)"},
      {"identification = { vendor_name = \"\", product_code = \"X\" }",
       "t.toml:4: profile.identification.vendor_name: must not be empty"},
      {"identification = \"Toshiba\"",
       "t.toml:4: profile.identification: must be a table such as { vendor_name = \"...\", "
       "product_code = \"...\" }"},
      {"identification = { vendor_name = \"T\", product_code = \"X\", model = \"Y\" }",
       "t.toml:4: profile.identification.model: unknown key (known: vendor_name, product_code)"},
  };
  for (const auto& [text, error] : cases) {
    EXPECT_EQ(errors_of(profile_with(text)), std::vector<std::string>{error}) << text;
  }
}

}  // namespace
}  // namespace drivegate::cli
