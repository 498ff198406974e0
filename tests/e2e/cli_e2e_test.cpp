// The programs' command lines: usage errors exit 2 with a message, configuration errors exit 1
// naming file and line, and the register map prints what the daemon serves. On a drive of the
// tests' own (test-drive, tests/support/test_adapter); the shipped examples and documents checked
// here name production adapters, and are checked where those are built.
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

// The first adapter `toml` names (`adapter = "ID"`) whose plugin is not built, or "".
std::string unbuilt_adapter_in(const std::string& toml) {
  const std::string key = "adapter = \"";
  for (auto at = toml.find(key); at != std::string::npos; at = toml.find(key, at + 1)) {
    const auto from = at + key.size();
    const std::string id = toml.substr(from, toml.find('"', from) - from);
    if (!adapter_built(id)) return id;
  }
  return "";
}

constexpr const char* kConfig = R"([server]
listen = "127.0.0.1:1502"

[[bus]]
name = "line"
port = "/dev/null"

[[device]]
name = "drive"
bus = "line"
adapter = "test-drive"
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
    if (const auto id = unbuilt_adapter_in(slurp(file)); !id.empty()) {
      GTEST_SKIP() << file << " names " << id << ", which is not built";
    }
    const auto r =
        run({drivegated(), "--check-config", file.string(), "--plugin-dir", plugin_dir().string()});
    EXPECT_EQ(r.status, 0) << file << ": " << r.out;
  }
}

// The installed example names every adapter built here among the values of `adapter`, and its
// commented-out modbus device, uncommented, is a valid part of it.
TEST(Cli, TheInstalledExampleNamesEveryAdapterAndItsModbusDeviceIsValid) {
  const auto example = std::filesystem::path(DRIVEGATE_SOURCE_DIR) / "etc/drivegate.toml";
  const std::string text = slurp(example);
  const auto adapter_key = text.find("#   adapter ");
  ASSERT_NE(adapter_key, std::string::npos);
  const std::string described =
      text.substr(adapter_key, text.find("#   unit_id", adapter_key) - adapter_key);
  std::size_t plugins = 0;
  for (const auto& f : std::filesystem::directory_iterator(plugin_dir())) {
    const std::string name = f.path().filename().string();
    if (!name.starts_with("drivegate-") || f.path().extension() != ".so") continue;
    const std::string id = name.substr(10, name.size() - 13);
    // The tests' own plugin (support/test_adapter) is in their directory, never installed.
    if (id == "test-drive") continue;
    ++plugins;
    EXPECT_THAT(described, HasSubstr(" " + id)) << "etc/drivegate.toml's adapter key lacks " << id;
  }
  EXPECT_GT(plugins, 0u);
  // The modbus device at the end, uncommented (where that adapter is built).
  if (!std::filesystem::exists(plugin_dir() / "drivegate-modbus.so")) return;
  const auto from = text.find("# [[bus]]\n# name = \"modbus-line\"");
  ASSERT_NE(from, std::string::npos);
  std::string uncommented = text.substr(0, from);
  std::istringstream rest(text.substr(from));
  for (std::string line; std::getline(rest, line);) {
    uncommented += (line.rfind("# ", 0) == 0 ? line.substr(2) : line == "#" ? "" : line) + "\n";
  }
  TempDir dir;
  std::ofstream(dir / "with-modbus.toml") << uncommented;
  const auto r = run({drivegated(), "--check-config", (dir / "with-modbus.toml").string(),
                      "--plugin-dir", plugin_dir().string()});
  EXPECT_EQ(r.status, 0) << uncommented.substr(from) << r.out;
  EXPECT_THAT(r.out, HasSubstr("OK (6 devices on 6 buses"));
}

// A profile's own options ([options.NAME]) are device options: checked as the configuration's
// own, naming the file and line, before anything runs.
constexpr const char* kPolesProfile = R"toml([profile]
name = "poles"
source = "a test"
[options.motor_poles]
default = 4
min = 2
max = 48
description = "motor poles"
[[point]]
name = "reference"
table = "holding"
address = 1   # a test's
type = "u16"
scale = 0.01
[common]
setpoint_rpm = { point = "reference", rpm_factor = "120 / motor_poles" }
)toml";

TEST(Cli, AProfilesOptionsAreCheckedAsTheConfigurationsOwn) {
  REQUIRE_ADAPTER("modbus");
  TempDir dir;
  std::ofstream(dir / "poles.toml") << kPolesProfile;
  const auto config = [&](const std::string& option) {
    std::ofstream(dir / "gw.toml") << "[[bus]]\nname = \"line\"\nport = \"/dev/null\"\n"
                                   << "[[device]]\nname = \"fan\"\nbus = \"line\"\n"
                                   << "adapter = \"modbus\"\nunit_id = 1\n[device.options]\n"
                                   << "profile = \"" << (dir / "poles.toml").string() << "\"\n"
                                   << option << "\n";
    return run({drivegated(), "--check-config", (dir / "gw.toml").string(), "--plugin-dir",
                plugin_dir().string()});
  };
  auto r = config("motor_poles = 2");
  EXPECT_EQ(r.status, 0) << r.out;
  r = config("motor_poles = 60");
  EXPECT_EQ(r.status, 1) << r.out;
  EXPECT_THAT(r.out, HasSubstr("gw.toml:11: device[0].options.motor_poles"));
  EXPECT_THAT(r.out, HasSubstr("2..48"));
  r = config("motor_poles = \"two\"");
  EXPECT_EQ(r.status, 1) << r.out;
  EXPECT_THAT(r.out, HasSubstr("gw.toml:11: device[0].options.motor_poles"));
  r = config("motor_poles = nan");
  EXPECT_EQ(r.status, 1) << r.out;
  EXPECT_THAT(r.out, HasSubstr("gw.toml:11: device[0].options.motor_poles"));
  r = config("poles = 2");
  EXPECT_EQ(r.status, 1) << r.out;
  EXPECT_THAT(r.out, HasSubstr("gw.toml:11: device[0].options.poles"));
  EXPECT_THAT(r.out, HasSubstr("unknown option"));
}

// A device whose options make a span of frequencies 0 or negative (the maximum at or below the
// minimum) has no rpm: a configuration error naming the device's line and what the factor is.
constexpr const char* kSpanProfile = R"toml([profile]
name = "span"
source = "a test"
[options.min_frequency_hz]
default = 10
min = 0
max = 320
description = "minimum frequency"
[options.max_frequency_hz]
default = 50
min = 1
max = 320
description = "maximum frequency"
[[point]]
name = "reference"
table = "holding"
address = 1   # a test's
type = "u16"
min = 0
max = 10000
[common]
setpoint_rpm = { point = "reference", rpm_factor = "(max_frequency_hz - min_frequency_hz) * 30 / 10000", rpm_offset = "min_frequency_hz * 30" }
)toml";

TEST(Cli, ADeviceWhoseOptionsMakeTheRpmFactorZeroOrNegativeIsAnError) {
  TempDir dir;
  std::ofstream(dir / "span.toml") << kSpanProfile;
  const auto config = [&](const std::string& options) {
    std::ofstream(dir / "gw.toml") << "[[bus]]\nname = \"line\"\nport = \"/dev/null\"\n"
                                   << "[[device]]\nname = \"fan\"\nbus = \"line\"\n"
                                   << "adapter = \"modbus\"\nunit_id = 1\n[device.options]\n"
                                   << "profile = \"" << (dir / "span.toml").string() << "\"\n"
                                   << options << "\n";
    return run({drivegated(), "--check-config", (dir / "gw.toml").string(), "--plugin-dir",
                plugin_dir().string()});
  };
  auto r = config("min_frequency_hz = 5\nmax_frequency_hz = 60");
  EXPECT_EQ(r.status, 0) << r.out;
  r = config("min_frequency_hz = 50\nmax_frequency_hz = 50");
  EXPECT_EQ(r.status, 1) << r.out;
  EXPECT_THAT(r.out, HasSubstr("gw.toml:4: device fan: "));
  EXPECT_THAT(r.out, HasSubstr("setpoint_rpm's rpm_factor '(max_frequency_hz - min_frequency_hz) "
                               "* 30 / 10000' is 0 with max_frequency_hz = 50, min_frequency_hz = "
                               "50: a factor must be above 0"));
  r = config("min_frequency_hz = 60");
  EXPECT_EQ(r.status, 1) << r.out;
  EXPECT_THAT(r.out, HasSubstr("gw.toml:4: device fan: "));
  EXPECT_THAT(r.out, HasSubstr("is -0.03 with max_frequency_hz = 50, min_frequency_hz = 60"));
}

TEST(Cli, ProfileCheckExitsZeroOneOrTwo) {
  TempDir dir;
  std::ofstream(dir / "poles.toml") << kPolesProfile;
  auto r = run({drivegate(), "profile", "check", (dir / "poles.toml").string()});
  EXPECT_EQ(r.status, 0) << r.out;  // warnings only: the common block is mostly unbound
  EXPECT_THAT(r.out, HasSubstr("warning: "));
  EXPECT_THAT(r.out, HasSubstr("not bound: speed_rpm, running, fault, fault_code, stop, "
                               "run_forward"));
  r = run({drivegate(), "profile", "check", "--strict", (dir / "poles.toml").string()});
  EXPECT_EQ(r.status, 1) << r.out;
  std::ofstream(dir / "bad.toml") << "[profile]\nname = \"bad\"\n";
  r = run({drivegate(), "profile", "check", (dir / "bad.toml").string(),
           (dir / "poles.toml").string()});
  EXPECT_EQ(r.status, 1) << r.out;
  EXPECT_THAT(r.out, HasSubstr("bad.toml:1: profile.source: required key is missing"));
  // A point of the device's own named as one of the common block's (the daemon would refuse the
  // device); a point the common block binds is not in the map under its own name, so any name is.
  std::string taken = kPolesProfile;
  taken.replace(taken.find("\"reference\""), 11, "\"command\"");
  taken.replace(taken.find("\"reference\""), 11, "\"command\"");
  std::ofstream(dir / "taken.toml") << taken;
  r = run({drivegate(), "profile", "check", (dir / "taken.toml").string()});
  EXPECT_EQ(r.status, 0) << r.out;
  std::ofstream(dir / "taken.toml", std::ios::app)
      << "[[point]]\nname = \"status\"\ntable = \"holding\"\naddress = 2   # a test's\n"
      << "type = \"u16\"\n";
  r = run({drivegate(), "profile", "check", (dir / "taken.toml").string()});
  EXPECT_EQ(r.status, 1) << r.out;
  EXPECT_THAT(r.out, HasSubstr("taken.toml:17: point.name: 'status' is a name of the common "
                               "block every device has"));
  EXPECT_EQ(run({drivegate(), "profile"}).status, 2);
  EXPECT_EQ(run({drivegate(), "profile", "lint", "x"}).status, 2);
  EXPECT_EQ(run({drivegate(), "profile", "check"}).status, 2);
  EXPECT_EQ(run({drivegate(), "profile", "check", "example-vfd"}).status, 0);  // by name
}

TEST(Cli, CheckConfigNamesFileLineAndKey) {
  TempDir dir;
  std::string text = kConfig;
  text.replace(text.find("unit_id = 1"), 11, "unit_id = 1\npoll = 5");
  std::ofstream(dir / "bad.toml") << text;
  const auto r = run({drivegated(), "--check-config", (dir / "bad.toml").string(), "--plugin-dir",
                      plugin_dir().string()});
  EXPECT_EQ(r.status, 1);
  EXPECT_THAT(r.out, HasSubstr("bad.toml:13: device[0].poll (device 'drive'): unknown key"));
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

// GNU command lines. A value after '=' or as the next word, the short options the man
// pages list, and a mistake named in one line followed by the usage, exit 2.
TEST(Cli, OptionsTakeTheirValueAfterAnEqualsSignOrAsTheNextWordShortOrLong) {
  TempDir dir;
  std::ofstream(dir / "bad.toml") << "[[device]]\nname = 1\n";
  const std::string bad = (dir / "bad.toml").string();
  for (const auto& argv : std::vector<std::vector<std::string>>{
           {drivegated(), "--config=" + bad, "--plugin-dir=" + plugin_dir().string()},
           {drivegated(), "-c", bad, "-p", plugin_dir().string()},
           {drivegated(), "-c" + bad, "-l", "warn", "--plugin-dir", plugin_dir().string()}}) {
    const auto r = run(argv);
    EXPECT_EQ(r.status, 1) << argv[1] << ": " << r.out;
    EXPECT_THAT(r.out, HasSubstr("bad.toml:2: device[0].name: must be a string")) << argv[1];
  }
  std::ofstream(dir / "gw.toml") << kConfig;
  const std::string good = (dir / "gw.toml").string();
  const auto check = run({drivegated(), "--check-config=" + good, "-p", plugin_dir().string()});
  EXPECT_EQ(check.status, 0) << check.out;
  EXPECT_THAT(check.out, HasSubstr("OK (1 devices on 1 buses, 1 listener)"));
  for (const auto& argv : std::vector<std::vector<std::string>>{
           {drivegate(), "regmap", "--config=" + good, "--format=md",
            "--plugin-dir=" + plugin_dir().string()},
           {drivegate(), "regmap", "-c", good, "-f", "md", "-p", plugin_dir().string()},
           {drivegate(), "regmap", "-fmd", "-p", plugin_dir().string(), "-c", good}}) {
    const auto r = run(argv);
    EXPECT_EQ(r.status, 0) << argv[2] << ": " << r.out;
    EXPECT_THAT(r.out, HasSubstr("## Unit 1: drive (test-drive)")) << argv[2];
  }
  const auto version = run({drivegated(), "-V"});
  EXPECT_EQ(version.status, 0);
  EXPECT_THAT(version.out, HasSubstr("drivegated "));
  EXPECT_EQ(run({drivegate(), "-V"}).status, 0);
}

TEST(Cli, ABadOptionExitsTwoNamingItThenTheUsage) {
  struct Case {
    std::vector<std::string> argv;
    std::string says;
    std::string usage;
  };
  const std::vector<Case> cases = {
      {{drivegated(), "--frobnicate"},
       "drivegated: unknown option '--frobnicate'\n",
       "usage: drivegated -c FILE"},
      {{drivegated(), "-x"}, "drivegated: unknown option '-x'\n", "usage: drivegated"},
      {{drivegated(), "--config"},
       "drivegated: option '--config' needs a value (FILE)\n",
       "usage: drivegated"},
      {{drivegated(), "-c", "x", "--log-level", "loud"},
       "drivegated: --log-level needs trace, debug, info, warn or error, not 'loud'\n",
       "usage: drivegated"},
      {{drivegate(), "--frobnicate"},
       "drivegate: unknown option '--frobnicate'\n",
       "usage: drivegate COMMAND"},
      {{drivegate(), "regmap", "--frobnicate", "x"},
       "drivegate regmap: unknown option '--frobnicate'\n",
       "usage: drivegate regmap -c FILE"},
      {{drivegate(), "capture", "-b", "x", "--seconds"},
       "drivegate capture: option '--seconds' needs a value (N)\n",
       "usage: drivegate capture"},
      {{drivegate(), "write", "-c"},
       "drivegate write: option '-c' needs a value (FILE)\n",
       "usage: drivegate write"},
      {{drivegate(), "sim", "ed3100", "--echo=yes"},
       "drivegate sim: option '--echo' takes no value\n",
       "usage: drivegate sim ADAPTER"},
      {{drivegate(), "demo", "--listen"},
       "drivegate demo: option '--listen' needs a value",
       "usage: drivegate demo"},
      {{drivegate(), "dcmd", "-c", "x", "-d", "y", "command"},
       "drivegate dcmd: 'command' is not METRIC=VALUE\n",
       "usage: drivegate dcmd -c FILE -d NAME"},
      {{drivegate(), "action", "--bogus"},
       "drivegate action: unknown option '--bogus'\n",
       "usage: drivegate action"},
      {{drivegate(), "scan", "--port", "/dev/ttyUSB0", "--baud", "fast"},
       "drivegate scan: --baud must be 300..921600, not 'fast'\n",
       "usage: drivegate scan --port DEVICE"},
  };
  for (const auto& c : cases) {
    const auto r = run(c.argv);
    EXPECT_EQ(r.status, 2) << c.argv.back() << ": " << r.out;
    EXPECT_EQ(r.out.rfind(c.says, 0), 0u) << "the first line names the option: " << r.out;
    EXPECT_THAT(r.out, HasSubstr(c.usage));
    EXPECT_THAT(r.out, HasSubstr("\noptions:\n"));
  }
}

// Each program's --help is its table of options; drivegate(1) documents every one of them (and
// the daemon's table is held to drivegated(8) by app_test's DaemonArgs tests).
TEST(Cli, HelpListsEveryOptionAndTheManPageDocumentsThem) {
  struct Command {
    std::vector<std::string> argv;
    std::vector<std::string> options;  // "-c, --config" or "--listen": the table, as printed
  };
  const std::vector<Command> commands = {
      {{drivegated(), "--help"},
       {"-c, --config FILE", "--check-config FILE", "--listen HOST:PORT", "-p, --plugin-dir DIR",
        "--state-dir DIR", "-l, --log-level LEVEL", "-V, --version", "-h, --help"}},
      {{drivegate(), "--help"}, {"-V, --version", "-h, --help"}},
      {{drivegate(), "regmap", "--help"},
       {"-c, --config FILE", "-f, --format FORMAT", "-p, --plugin-dir DIR", "-h, --help"}},
      {{drivegate(), "write", "-h"},
       {"-c, --config FILE", "-d, --device NAME", "-t, --timeout-ms N", "-p, --plugin-dir DIR",
        "-h, --help"}},
      {{drivegate(), "action", "--help"},
       {"-c, --config FILE", "-d, --device NAME", "-t, --timeout-ms N", "-p, --plugin-dir DIR",
        "-h, --help"}},
      {{drivegate(), "capture", "--help"},
       {"-b, --bus NAME", "-s, --seconds N", "-w, --write FILE", "-c, --config FILE",
        "--http HOST:PORT", "--progress", "--no-progress", "-h, --help"}},
      {{drivegate(), "demo", "--help"},
       {"-l, --listen HOST:PORT", "--no-start", "-p, --plugin-dir DIR", "-h, --help"}},
      {{drivegate(), "sim", "--help"},
       {"-a, --address N", "--set OPTION=VALUE", "--cmd LINE", "--link PATH", "--port DEVICE",
        "--baud N", "--parity PARITY", "--echo", "--no-echo", "--turnaround-ms N",
        "--turnaround-us N", "--wire-timing", "--wire-log FILE", "-p, --plugin-dir DIR",
        "-h, --help"}},
      {{drivegate(), "dcmd", "--help"},
       {"-c, --config FILE", "-d, --device NAME", "-t, --timeout-ms N", "-p, --plugin-dir DIR",
        "-h, --help"}},
      {{drivegate(), "protocol", "--help"},
       {"--request", "--reply", "--set OPTION=VALUE", "-h, --help"}},
      {{drivegate(), "events", "--help"},
       {"-f, --follow", "-n, --lines N", "-d, --device NAME", "-k, --kind KIND",
        "-c, --config FILE", "--http HOST:PORT", "-h, --help"}},
      {{drivegate(), "scan", "--help"},
       {"--port DEVICE", "--baud N", "--parity PARITY", "--data-bits N", "--stop-bits N",
        "--framing FRAMING", "--rs485", "-a, --addresses LIST", "-t, --timeout-ms N",
        "--profiles DIR", "--progress", "--no-progress", "-h, --help"}},
  };
  std::ifstream in(std::filesystem::path(DRIVEGATE_SOURCE_DIR) / "packaging/man/drivegate.1");
  const std::string page((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_FALSE(page.empty());
  const auto troff = [](const std::string& option) {
    std::string out;
    for (const char c : option) out += c == '-' ? std::string("\\-") : std::string(1, c);
    return out;
  };
  for (const auto& c : commands) {
    const auto r = run(c.argv);
    EXPECT_EQ(r.status, 0) << c.argv[1];
    const auto options = r.out.find("\noptions:\n");
    ASSERT_NE(options, std::string::npos) << r.out;
    std::istringstream lines(r.out);
    for (std::string line; std::getline(lines, line);) {
      EXPECT_LE(line.size(), 79u) << "wider than a terminal: " << line;
    }
    std::size_t listed = 0;
    for (std::size_t at = options; (at = r.out.find("\n  ", at + 1)) != std::string::npos;) {
      if (r.out.compare(at + 3, 1, "-") == 0 || r.out.compare(at + 3, 5, "    -") == 0) ++listed;
    }
    EXPECT_EQ(listed, c.options.size()) << "options beyond the test's list: " << r.out;
    for (const auto& o : c.options) {
      EXPECT_THAT(r.out.substr(options), HasSubstr(o)) << c.argv[1];
      if (c.argv[0] == drivegated()) continue;
      const std::string long_name =
          o.substr(o.find("--"), o.find(' ', o.find("--")) - o.find("--"));
      EXPECT_THAT(page, HasSubstr(troff(long_name))) << "drivegate(1) lacks " << long_name;
      if (o[1] != '-') {
        EXPECT_THAT(page, HasSubstr(troff(o.substr(0, 2)) + " \", \" " + troff(long_name)))
            << "drivegate(1) lacks " << o.substr(0, 2) << " beside " << long_name;
      }
    }
  }
}

// docs/register-map.md is what `drivegate regmap` prints for docs/register-map.toml (one fact, one
// place): a change to the map or its printing that leaves the printed map behind fails here.
TEST(Cli, TheRegisterMapInTheDocsIsWhatRegmapPrints) {
  const std::filesystem::path docs = std::filesystem::path(DRIVEGATE_SOURCE_DIR) / "docs";
  if (const auto id = unbuilt_adapter_in(slurp(docs / "register-map.toml")); !id.empty()) {
    GTEST_SKIP() << "docs/register-map.toml names " << id << ", which is not built";
  }
  const auto r = run({drivegate(), "regmap", "--config", (docs / "register-map.toml").string(),
                      "--format", "md", "--plugin-dir", plugin_dir().string()});
  ASSERT_EQ(r.status, 0) << r.out;
  std::string doc = slurp(docs / "register-map.md");
  // The file says where it comes from, after its title; the rest is the command's output.
  const std::string provenance = "register-map.md`.\n";
  const auto from = doc.find("\n\nThe demo's ");
  const auto to = doc.find(provenance);
  ASSERT_NE(from, std::string::npos);
  ASSERT_NE(to, std::string::npos);
  doc.erase(from + 1, to + provenance.size() - from - 1);
  const auto trimmed = [](std::string t) {
    while (!t.empty() && t.back() == '\n') t.pop_back();
    return t;
  };
  EXPECT_EQ(trimmed(doc), trimmed(r.out))
      << "regenerate: drivegate regmap --config docs/register-map.toml --format md";
}

TEST(Cli, RegmapPrintsTheServedMap) {
  TempDir dir;
  std::ofstream(dir / "gw.toml") << kConfig;
  const auto r = run({drivegate(), "regmap", "--config", (dir / "gw.toml").string(), "--format",
                      "json", "--plugin-dir", plugin_dir().string()});
  EXPECT_EQ(r.status, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("{\"unit_id\": 1, \"name\": \"drive\", \"adapter\": "
                               "\"test-drive\""));
  EXPECT_THAT(r.out, HasSubstr("{\"name\": \"speed_rpm\", \"table\": \"input\", \"address\": 6, "
                               "\"reference\": \"30007\", \"type\": \"i16\""));
  const auto md = run({drivegate(), "regmap", "--config", (dir / "gw.toml").string(), "--format",
                       "md", "--plugin-dir", plugin_dir().string()});
  EXPECT_THAT(md.out, HasSubstr("## Unit 1: drive (test-drive)"));
}

// The tools that ask the running daemon find it where its configuration says: `--config FILE`'s
// [http] listen (--http overrides it). A file without [http], a daemon not running, a capture
// the file does not serve: each is said naming the file and the address, never a bare
// "Connection refused" at a default address.
TEST(Cli, EventsAndCaptureFindTheDaemonFromItsConfiguration) {
  TempDir dir;
  Sim sim("test-drive", dir / "drive");
  const int http_port = free_port();
  const std::string toml = "[http]\nlisten = \"127.0.0.1:" + std::to_string(http_port) +
                           "\"\n\n[[bus]]\nname = \"line\"\nport = \"" + (dir / "drive").string() +
                           "\"\n\n[[device]]\nname = \"drive\"\nbus = \"line\"\n"
                           "adapter = \"test-drive\"\nunit_id = 1\n";
  const std::string file = (dir / "drivegate.toml").string();
  const std::string at = "127.0.0.1:" + std::to_string(http_port);
  {
    // Written, the daemon not started yet: refused, and said where and why.
    std::ofstream(file) << toml;
    const auto refused = run({drivegate(), "events", "--config", file});
    EXPECT_EQ(refused.status, 1) << refused.out;
    EXPECT_THAT(refused.out,
                HasSubstr("drivegate events: " + at + " (the [http] listen of " + file +
                          "): Connection refused; is drivegated running "
                          "with " +
                          file + "?"));
  }
  Daemon daemon(dir, toml);
  const auto events = run({drivegate(), "events", "-c", daemon.config().string()});
  EXPECT_EQ(events.status, 0) << events.out;
  EXPECT_THAT(events.out, HasSubstr("Modbus listener"));
  // --http still wins over the file, which is then not read.
  const auto direct = run(
      {drivegate(), "events", "--config", (dir / "none.toml").string(), "--http", at, "-n", "1"});
  EXPECT_EQ(direct.status, 0) << direct.out;
  // The file serves no captures: said before anything is asked.
  const auto capture =
      run({drivegate(), "capture", "-b", "line", "-s", "1", "-c", daemon.config().string()});
  EXPECT_EQ(capture.status, 1) << capture.out;
  EXPECT_THAT(capture.out, HasSubstr("says [http] capture = false: the daemon serves no captures"));

  // A configuration without [http]: the daemon has no HTTP side to ask.
  std::ofstream(dir / "no-http.toml") << toml.substr(toml.find("[[bus]]"));
  for (const char* command : {"events", "capture"}) {
    std::vector<std::string> argv = {drivegate(), command, "-c", (dir / "no-http.toml").string()};
    if (std::string(command) == "capture") argv.insert(argv.end(), {"-b", "line"});
    const auto none = run(argv);
    EXPECT_EQ(none.status, 1) << none.out;
    EXPECT_THAT(none.out, HasSubstr("drivegate " + std::string(command) + ": " +
                                    (dir / "no-http.toml").string() +
                                    " has no [http]: the daemon serves no HTTP side to ask"));
  }
  // One that cannot be read, or does not validate, is said to be the reason.
  const auto missing = run({drivegate(), "events", "-c", (dir / "none.toml").string()});
  EXPECT_EQ(missing.status, 1) << missing.out;
  EXPECT_THAT(missing.out, HasSubstr("cannot tell where the daemon's HTTP side is from " +
                                     (dir / "none.toml").string()));
  std::ofstream(dir / "bad.toml") << "[http]\nlisten = \"nowhere\"\n";
  const auto bad = run({drivegate(), "events", "-c", (dir / "bad.toml").string()});
  EXPECT_EQ(bad.status, 1) << bad.out;
  EXPECT_THAT(bad.out, HasSubstr("bad.toml:2: http.listen: "));
}

// A port has one owner. `drivegate write` on a line the daemon runs says at once who
// owns it, instead of sharing the line and timing out (0x0B); with the daemon stopped it works.
TEST(Cli, WriteOnAPortTheDaemonOwnsNamesTheOwner) {
  TempDir dir;
  Sim sim("test-drive", dir / "drive");
  const std::string toml = "[[bus]]\nname = \"line\"\nport = \"" + (dir / "drive").string() +
                           "\"\n\n[[device]]\nname = \"drive\"\nbus = \"line\"\n"
                           "adapter = \"test-drive\"\nunit_id = 1\n";
  Daemon daemon(dir, toml);
  Plc plc(daemon.port());
  ASSERT_TRUE(plc.connect());
  ASSERT_TRUE(
      eventually([&] { return (plc.input(reg::status, 1).regs.at(0) & reg::online) != 0; }, 10s));
  const std::vector<std::string> write = {
      drivegate(),    "write", "--config",     daemon.config().string(),
      "--device",     "drive", "--plugin-dir", plugin_dir().string(),
      "accel_time=30"};
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
