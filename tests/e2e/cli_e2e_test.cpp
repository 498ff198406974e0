// The programs' command lines: usage errors exit 2 with a message, configuration errors exit 1
// naming file and line, and the register map prints what the daemon serves.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "e2e.h"

namespace drivegate::test {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;

struct Result {
  int status;
  std::string out;
};

// Runs a program to completion, stdout and stderr together.
Result run(std::vector<std::string> argv) {
  argv.insert(argv.begin(), {"/bin/sh", "-c", "exec \"$0\" \"$@\" 2>&1"});
  Child child(argv);
  std::string out;
  while (auto line = child.read_line(std::chrono::seconds(20))) out += *line + "\n";
  return {child.stop(0), out};
}

std::string drivegated() {
  return (bin_dir() / "drivegated").string();
}
std::string drivegate() {
  return (bin_dir() / "drivegate").string();
}

constexpr const char* kConfig = R"([server]
listen = "127.0.0.1:1502"

[[bus]]
name = "line"
port = "/dev/null"

[[device]]
name = "washer"
bus = "line"
adapter = "nidec-washer"
unit_id = 1
)";

TEST(Cli, CheckConfigAcceptsAGoodFile) {
  TempDir dir;
  std::ofstream(dir / "good.toml") << kConfig;
  const auto r = run({drivegated(), "--check-config", (dir / "good.toml").string(), "--plugin-dir",
                      plugin_dir().string()});
  EXPECT_EQ(r.status, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("OK (1 devices on 1 buses, 1 listener)"));
  // [server] listen serves every address with every right, as it always did: valid, but said.
  EXPECT_THAT(r.out, HasSubstr(":2: server.listen: 127.0.0.1:1502 lets every address that can "
                               "reach it write (access maintain)"));
}

// The configurations people copy from must stay valid: the README's sample and the installed
// example (both name ports that need not exist; --check-config does not open them).
TEST(Cli, TheDocumentedConfigurationsAreValid) {
  std::ifstream readme(std::filesystem::path(DRIVEGATE_SOURCE_DIR) / "README.md");
  std::string text((std::istreambuf_iterator<char>(readme)), std::istreambuf_iterator<char>());
  const auto start = text.find("```toml\n");
  ASSERT_NE(start, std::string::npos);
  const auto end = text.find("```", start + 8);
  TempDir dir;
  std::ofstream(dir / "readme.toml") << text.substr(start + 8, end - start - 8);
  for (const auto& file :
       {dir / "readme.toml", std::filesystem::path(DRIVEGATE_SOURCE_DIR) / "etc/drivegate.toml"}) {
    const auto r =
        run({drivegated(), "--check-config", file.string(), "--plugin-dir", plugin_dir().string()});
    EXPECT_EQ(r.status, 0) << file << ": " << r.out;
  }
}

TEST(Cli, CheckConfigNamesFileLineAndKey) {
  TempDir dir;
  std::string text = kConfig;
  text.replace(text.find("unit_id = 1"), 11, "unit_id = 1\npoll = 5");
  std::ofstream(dir / "bad.toml") << text;
  const auto r = run({drivegated(), "--check-config", (dir / "bad.toml").string(), "--plugin-dir",
                      plugin_dir().string()});
  EXPECT_EQ(r.status, 1);
  EXPECT_THAT(r.out, HasSubstr("bad.toml:13: device[0].poll: unknown key"));
}

TEST(Cli, DaemonRefusesABadConfigWithExitOne) {
  TempDir dir;
  std::ofstream(dir / "bad.toml") << "[[device]]\nname = 1\n";
  const auto r = run({drivegated(), "--config", (dir / "bad.toml").string(), "--plugin-dir",
                      plugin_dir().string()});
  EXPECT_EQ(r.status, 1);
  EXPECT_THAT(r.out, HasSubstr("bad.toml:2: device[0].name: must be a string"));
}

TEST(Cli, UsageErrorsExitTwo) {
  EXPECT_EQ(run({drivegated(), "--frobnicate"}).status, 2);
  EXPECT_EQ(run({drivegated()}).status, 2);
  EXPECT_EQ(run({drivegated(), "--listen", "nowhere"}).status, 2);
  EXPECT_EQ(run({drivegate()}).status, 2);
  EXPECT_EQ(run({drivegate(), "frobnicate"}).status, 2);
  EXPECT_EQ(run({drivegate(), "regmap"}).status, 2);
  const auto sim =
      run({drivegate(), "sim", "no-such-adapter", "--plugin-dir", plugin_dir().string()});
  EXPECT_EQ(sim.status, 1);
  EXPECT_THAT(sim.out, HasSubstr("no adapter 'no-such-adapter'"));
}

TEST(Cli, RegmapPrintsTheServedMap) {
  TempDir dir;
  std::ofstream(dir / "gw.toml") << kConfig;
  const auto r = run({drivegate(), "regmap", "--config", (dir / "gw.toml").string(), "--format",
                      "json", "--plugin-dir", plugin_dir().string()});
  EXPECT_EQ(r.status, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("{\"unit_id\": 1, \"name\": \"washer\", \"adapter\": "
                               "\"nidec-washer\""));
  EXPECT_THAT(r.out, HasSubstr("{\"name\": \"speed_rpm\", \"table\": \"input\", \"address\": 6, "
                               "\"type\": \"i16\""));
  const auto md = run({drivegate(), "regmap", "--config", (dir / "gw.toml").string(), "--format",
                       "md", "--plugin-dir", plugin_dir().string()});
  EXPECT_THAT(md.out, HasSubstr("## Unit 1: washer (nidec-washer)"));
}

// Issue 24: a port has one owner. `drivegate write` on a line the daemon runs says at once who
// owns it, instead of sharing the line and timing out (0x0B); with the daemon stopped it works.
TEST(Cli, WriteOnAPortTheDaemonOwnsNamesTheOwner) {
  TempDir dir;
  Sim sim("nidec-washer", dir / "washer");
  const std::string toml = "[[bus]]\nname = \"line\"\nport = \"" + (dir / "washer").string() +
                           "\"\n\n[[device]]\nname = \"washer\"\nbus = \"line\"\n"
                           "adapter = \"nidec-washer\"\nunit_id = 1\n";
  Daemon daemon(dir, toml);
  Plc plc(daemon.port());
  ASSERT_TRUE(plc.connect());
  ASSERT_TRUE(eventually([&] { return (plc.input(reg::status, 1).regs.at(0) & reg::online) != 0; },
                         10s));
  const std::vector<std::string> write = {drivegate(), "write", "--config",
                                          daemon.config().string(), "--device", "washer",
                                          "--plugin-dir", plugin_dir().string(), "accel_time=30"};
  const auto asked = std::chrono::steady_clock::now();
  const auto busy = run(write);
  EXPECT_EQ(busy.status, 1) << busy.out;
  EXPECT_THAT(busy.out, HasSubstr("is in use by drivegated (pid "));
  EXPECT_LT(std::chrono::steady_clock::now() - asked, 5s);  // at once, not after a timeout
  ASSERT_EQ(daemon.stop(), 0);
  const auto free = run(write);
  EXPECT_EQ(free.status, 0) << free.out;
  EXPECT_THAT(free.out, HasSubstr("accel_time=30: ok"));
}

}  // namespace
}  // namespace drivegate::test
