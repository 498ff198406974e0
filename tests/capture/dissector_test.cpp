// The Wireshark plugin folder the build assembles (build/wireshark/, tools/wireshark/README.md)
// in tshark, on golden frames in a pcap written by capture/pcap_format.h: each adapter's own
// dissector and the framed dissector on the data `drivegate protocol dissector` generated from
// each shipped description. Every frame is named by its protocol, its message in the Info column
// and every checksum verified: Good on the frame as sent, Bad on one byte changed. No Lua error,
// no packet malformed. A frame whose adapter is not built is left out.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "capture/pcap_format.h"
#include "temp_dir.h"

namespace drivegate::capture {
namespace {

struct Golden {
  std::string adapter;   // the capture's adapter id: an adapter's, or "framed/NAME"
  int direction;         // 0 gateway -> drive, 1 drive -> gateway
  std::string hex;       // the frame on the wire
  std::string protocol;  // tshark's Protocol column
  std::string info;      // tshark's Info column
  std::string status;    // the checksum status fields' values, comma-separated (1 Good, 0 Bad)
};

// Frames of the vendor documents (/work/shared/specs, README there); a "bad" row is the one above
// it with its last checksum byte changed.
const std::vector<Golden> kGolden = {
    // Described protocols: the shipped descriptions' generated data.
    {"framed/nidec-washer", 0, "A5 05 00 00 00 00 00 00 00 00 A0", "NIDEC-WASHER", "request", "1"},
    {"framed/nidec-washer", 0, "A5 05 00 00 00 00 00 00 00 00 A1", "NIDEC-WASHER",
     "request [bad checksum]", "0"},
    {"framed/nidec-washer", 1, "A5 05 00 03 20 23 A0", "NIDEC-WASHER", "request_ack", "1"},
    {"framed/mdriver-2400", 0, "00 01 10 02 40 01 00 01", "MDRIVER-2400", "run", "1"},
    {"framed/mdriver-2400", 1, "01 00 10 08 40 3E 00 00 2A 01 02 03 8E", "MDRIVER-2400",
     "run_reply", "1"},
    {"framed/fdc1", 0, "48 73 07 D0 0D AC 55 18", "FDC1", "speed", "1"},
    {"framed/fdc1", 1, "1B 4C 0B B8 01 2C 11 D8", "FDC1", "status_on", "1,1"},
    {"framed/fdc1", 1, "1B 4C 0B B8 01 2C 11 D9", "FDC1", "status_on [bad ce]", "1,0"},
    {"framed/fdc1", 1, "1B 4C 00 31 00 10 1B 6D", "FDC1", "status_off", "1,1"},
    {"framed/fdc1", 0, "01 02 03", "FDC1", "Unknown frame, 3 bytes", ""},
    // The adapters' own dissectors, on the same frames where the protocol is the same.
    {"nidec-washer", 0, "A5 05 00 00 00 00 00 00 00 00 A0", "NIDEC-WASHER", "Request", "1"},
    {"nidec-washer", 1, "A5 05 00 03 20 23 A0", "NIDEC-WASHER", "Reply Request", "1"},
    {"mdriver-2400", 0, "00 01 10 02 40 01 00 01", "MDRIVER-2400", "Run, code 0x40", "1"},
    {"mdriver-2400", 1, "01 00 10 08 40 3E 00 00 2A 01 02 03 8E", "MDRIVER-2400",
     "Run reply, actual 0x3e", "1"},
    {"fdc1", 0, "48 73 07 D0 0D AC 55 18", "FDC1", "Speed programming: 2000..3500 rpm", "1"},
    {"fdc1", 1, "1B 4C 0B B8 01 2C 11 D9", "FDC1", "Status: motor on, 3000 rpm", "1,0"},
    {"ed3100", 0, "01 03 0E 01 00 01 D7 22", "ED3100", "Read registers 0x0e01 x1", "1"},
    {"ed3100", 1, "01 03 0E 01 00 05 D6 E1", "ED3100", "Read registers reply 0x0e01", "1"},
    {"modbus", 0, "01 03 00 00 00 02 C4 0B", "MODBUS", "Read holding registers 0 x2", "1"},
    {"modbus", 1, "01 03 04 00 01 00 02 2A 32", "MODBUS", "Read holding registers reply", "1"},
    {"modbus", 1, "01 03 04 00 01 00 02 2A 33", "MODBUS", "Read holding registers reply", "0"},
    {"unicla-edrive", 0, "7E 01 10 C1 C0 05 00 00 02 0B B8 D1 64 7E", "UNICLA-EDRIVE",
     "Write Set run state, 3000 rpm, seq 5", "1"},
    {"unicla-edrive", 0, "7E 01 10 C0 01 07 00 00 00 35 E4 7E", "UNICLA-EDRIVE",
     "Read Status, seq 7", "1"},
};

// The checksum status fields of every protocol above, in the order tshark prints them.
const std::vector<std::string> kStatusFields = {"framed_nidec_washer.checksum.status",
                                                "framed_mdriver_2400.checksum.status",
                                                "framed_fdc1.checksum.status",
                                                "nidec_washer.checksum.status",
                                                "mdriver2400.checksum.status",
                                                "fdc1.checksum.status",
                                                "ed3100.crc.status",
                                                "drivegate_modbus.crc.status",
                                                "unicla_edrive.crc.status"};

std::filesystem::path plugin_folder() {
  return DRIVEGATE_TEST_WIRESHARK_DIR;
}

// The plugin folder's dissector of the adapter of a capture's adapter id ("framed/NAME": framed,
// whose data for NAME must then be there too): drivegate_<adapter>.lua, '-' as '_'.
std::filesystem::path adapter_dissector(const std::string& capture_id) {
  std::string id = capture_id.substr(0, capture_id.find('/'));
  for (char& c : id) {
    if (c == '-') c = '_';
  }
  return plugin_folder() / ("drivegate_" + id + ".lua");
}

std::vector<std::uint8_t> bytes_of(const std::string& hex) {
  std::vector<std::uint8_t> out;
  std::istringstream in(hex);
  unsigned byte = 0;
  while (in >> std::hex >> byte) out.push_back(static_cast<std::uint8_t>(byte));
  return out;
}

// `command`'s stdout and stderr, line by line.
std::vector<std::string> run_lines(const std::string& command) {
  std::vector<std::string> lines;
  FILE* p = ::popen((command + " 2>&1").c_str(), "r");
  if (p == nullptr) return lines;
  std::string line;
  for (int c = std::fgetc(p); c != EOF; c = std::fgetc(p)) {
    if (c != '\n') {
      line.push_back(static_cast<char>(c));
      continue;
    }
    lines.push_back(line);
    line.clear();
  }
  ::pclose(p);
  return lines;
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out(1);
  for (const char c : s) {
    if (c == sep) {
      out.emplace_back();
    } else {
      out.back().push_back(c);
    }
  }
  return out;
}

TEST(Dissectors, DecodeGoldenFramesWithEveryChecksumVerified) {
  if (!std::filesystem::exists("/usr/bin/tshark")) {
    GTEST_SKIP() << "tshark is not installed (tools/deps.sh tshark)";
  }
  ASSERT_TRUE(std::filesystem::exists(plugin_folder() / "drivegate.lua"));
  std::vector<Golden> cases;
  for (const auto& g : kGolden) {
    if (std::filesystem::exists(adapter_dissector(g.adapter))) cases.push_back(g);
  }
  ASSERT_FALSE(cases.empty()) << "no dissector in " << plugin_folder();
  const test::TempDir dir;
  std::string pcap = pcap_global_header();
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const auto bytes = bytes_of(cases[i].hex);
    append_pcap_record(pcap, {.unix_us = 1'700'000'000'000'000 + static_cast<std::int64_t>(i),
                              .direction = static_cast<std::uint8_t>(cases[i].direction),
                              .unit_id = 1,
                              .adapter = cases[i].adapter,
                              .device = "drive",
                              .bytes = bytes});
  }
  const auto file = dir / "golden.pcap";
  std::ofstream(file, std::ios::binary) << pcap;
  const std::string tshark = "/usr/bin/tshark -r '" + file.string() +
                             "' -X 'lua_script:" + (plugin_folder() / "drivegate.lua").string() +
                             "'";

  // The whole dissection, as text: no Lua error, no dissector thrown out of a frame (a frame no
  // message fits is the description's verdict, an expert item, not a malformed packet).
  const auto verbose = run_lines(tshark + " -V");
  ASSERT_FALSE(verbose.empty());
  for (const auto& line : verbose) {
    EXPECT_THAT(line, ::testing::Not(::testing::HasSubstr("Lua"))) << line;
    EXPECT_THAT(line, ::testing::Not(::testing::HasSubstr("Malformed Packet"))) << line;
  }
  // Frame by frame: protocol, Info, every checksum status.
  std::string fields = " -T fields -E separator=/t -e _ws.col.Protocol -e _ws.col.Info";
  for (const auto& f : kStatusFields) fields += " -e " + f;
  std::vector<std::string> rows;
  for (auto& line : run_lines(tshark + fields)) {
    if (line.find("Running as user") == std::string::npos) rows.push_back(std::move(line));
  }
  ASSERT_EQ(rows.size(), cases.size());
  for (std::size_t i = 0; i < cases.size(); ++i) {
    SCOPED_TRACE(cases[i].adapter + ": " + cases[i].hex);
    const auto f = split(rows[i], '\t');
    ASSERT_EQ(f.size(), 2 + kStatusFields.size()) << rows[i];
    EXPECT_EQ(f[0], cases[i].protocol);
    EXPECT_EQ(f[1], cases[i].info);
    std::string status;
    for (std::size_t k = 2; k < f.size(); ++k) status += f[k];
    EXPECT_EQ(status, cases[i].status);
  }
}

}  // namespace
}  // namespace drivegate::capture
