// The configuration loader: good files load with adapter defaults filled in; every kind of bad
// file is refused with the file, line and key named.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <limits>

#include "config/config_loader.h"
#include "fake_adapter.h"
#include "plugin/adapter_options.h"

namespace drivegate {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::IsEmpty;
using ::testing::Not;

class ConfigTest : public ::testing::Test {
 protected:
  ConfigTest() {
    plugins_.add(test::kFakeAdapter);
    plugins_.add(test::kFakeStreamer);
  }
  ConfigResult parse(const std::string& text) { return parse_config(text, "gw.toml", plugins_); }
  std::string only_error(const std::string& text) {
    auto r = parse(text);
    EXPECT_FALSE(r.config.has_value());
    EXPECT_EQ(r.errors.size(), 1u) << ::testing::PrintToString(r.errors);
    return r.errors.empty() ? "" : r.errors.front();
  }
  PluginRegistry plugins_;
};

constexpr const char* kGood = R"(
[server]
listen = "127.0.0.1:1502"
max_clients = 8

[[bus]]
name = "line1"
port = "/dev/ttyUSB0"

[[device]]
name = "washer"
bus = "line1"
adapter = "fake"
unit_id = 3
address = 5
poll_ms = 250
[device.options]
count = 9
names = ["x", "y", "z"]
)";

TEST(ConfigListen, ParsesHostPortForms) {
  auto s = parse_listen("127.0.0.1:1502");
  ASSERT_TRUE(s);
  EXPECT_EQ(s->host, "127.0.0.1");
  EXPECT_EQ(s->port, 1502);
  s = parse_listen("[::1]:502");
  ASSERT_TRUE(s);
  EXPECT_EQ(s->host, "::1");
  s = parse_listen(":502");
  ASSERT_TRUE(s);
  EXPECT_EQ(s->host, "0.0.0.0");
  EXPECT_FALSE(parse_listen("localhost"));
  EXPECT_FALSE(parse_listen("h:70000"));
  EXPECT_FALSE(parse_listen("h:12ab"));
}

TEST_F(ConfigTest, GoodFileLoadsWithAdapterDefaults) {
  auto r = parse(kGood);
  ASSERT_TRUE(r.config) << ::testing::PrintToString(r.errors);
  const Config& c = *r.config;
  ASSERT_EQ(c.listeners.size(), 1u);  // [server] listen: one plain listener, as always
  EXPECT_EQ(c.listeners[0].host, "127.0.0.1");
  EXPECT_EQ(c.listeners[0].port, 1502);
  EXPECT_EQ(c.listeners[0].policy.access, AccessLevel::maintain);
  EXPECT_TRUE(c.listeners[0].policy.allow.empty());
  EXPECT_TRUE(c.listeners[0].from_server_listen);
  EXPECT_EQ(c.server.max_clients, 8u);
  ASSERT_EQ(c.buses.size(), 1u);
  // Line settings not given come from the adapter: 4800 8O1 with echo.
  EXPECT_EQ(c.buses[0].baud, 4800u);
  EXPECT_EQ(c.buses[0].parity, Parity::odd);
  EXPECT_EQ(c.buses[0].data_bits, 8);
  EXPECT_EQ(c.buses[0].stop_bits, 1);
  EXPECT_TRUE(c.buses[0].echo);
  ASSERT_EQ(c.devices.size(), 1u);
  const DeviceConfig& d = c.devices[0];
  EXPECT_EQ(d.unit_id, 3);
  EXPECT_EQ(d.address, 5u);
  EXPECT_EQ(d.poll_interval, Millis(250));
  EXPECT_EQ(d.options.integer("count"), 9);
  EXPECT_DOUBLE_EQ(d.options.real("ratio"), 0.5);
  EXPECT_FALSE(d.options.boolean("enabled"));
  EXPECT_EQ(d.options.string("mode"), "normal");
  EXPECT_EQ(d.options.string_list("names"), (std::vector<std::string>{"x", "y", "z"}));
}

TEST_F(ConfigTest, BusSettingsOverrideTheAdapter) {
  std::string text = kGood;
  text.replace(
      text.find("port = \"/dev/ttyUSB0\""), 21,
      "port = \"/dev/ttyUSB0\"\nbaud = 9600\nparity = \"even\"\nstop_bits = 2\necho = false");
  auto r = parse(text);
  ASSERT_TRUE(r.config) << ::testing::PrintToString(r.errors);
  EXPECT_EQ(r.config->buses[0].baud, 9600u);
  EXPECT_EQ(r.config->buses[0].parity, Parity::even);
  EXPECT_EQ(r.config->buses[0].stop_bits, 2);
  EXPECT_FALSE(r.config->buses[0].echo);
}

TEST_F(ConfigTest, UnknownKeyNamesFileLineAndKey) {
  std::string text = kGood;
  text.replace(text.find("poll_ms = 250"), 13, "poll_ms = 250\npol_ms = 5");
  EXPECT_THAT(only_error(text), AllOf(HasSubstr("gw.toml:17:"), HasSubstr("device[0].pol_ms"),
                                      HasSubstr("unknown key")));
}

TEST_F(ConfigTest, WrongTypeIsNamed) {
  std::string text = kGood;
  text.replace(text.find("unit_id = 3"), 11, "unit_id = \"3\"");
  EXPECT_THAT(only_error(text),
              AllOf(HasSubstr("gw.toml:14:"), HasSubstr("unit_id"), HasSubstr("integer")));
}

TEST_F(ConfigTest, OutOfRangeValuesAreRefused) {
  std::string text = kGood;
  text.replace(text.find("unit_id = 3"), 11, "unit_id = 248");
  EXPECT_THAT(only_error(text), AllOf(HasSubstr("unit_id"), HasSubstr("1..247")));
  text = kGood;
  text.replace(text.find("address = 5"), 11, "address = 32");
  EXPECT_THAT(only_error(text), AllOf(HasSubstr("address"), HasSubstr("1..31")));
}

// [history]: a bound for each shelf of the event history, 0 keeping none there.
TEST_F(ConfigTest, TheHistoryHasABoundForEachShelf) {
  auto r = parse(std::string(kGood) + "[history]\nevents = 10\ncommands = 20\nrefusals = 0\n");
  ASSERT_TRUE(r.config.has_value()) << ::testing::PrintToString(r.errors);
  EXPECT_EQ(r.config->history.events, 10u);
  EXPECT_EQ(r.config->history.commands, 20u);
  EXPECT_EQ(r.config->history.refusals, 0u);
  r = parse(kGood);
  ASSERT_TRUE(r.config.has_value());
  EXPECT_EQ(r.config->history.commands, 2000u);
  EXPECT_EQ(r.config->history.refusals, 2000u);
  EXPECT_THAT(only_error(std::string(kGood) + "[history]\nrefusals = 100001\n"),
              AllOf(HasSubstr("refusals"), HasSubstr("0..100000")));
}

TEST_F(ConfigTest, AdapterOptionsAreCheckedAgainstTheSchema) {
  std::string text = kGood;
  text.replace(text.find("count = 9"), 9, "count = 11");
  EXPECT_THAT(only_error(text), AllOf(HasSubstr("gw.toml:18:"), HasSubstr("options.count")));
  text = kGood;
  text.replace(text.find("count = 9"), 9, "mode = \"turbo\"");
  EXPECT_THAT(only_error(text), HasSubstr("normal|continuous"));
  text = kGood;
  text.replace(text.find("count = 9"), 9, "colour = 1");
  EXPECT_THAT(only_error(text),
              AllOf(HasSubstr("options.colour"), HasSubstr("unknown option for adapter 'fake'")));
}

TEST_F(ConfigTest, UnknownAdapterListsTheInstalledOnes) {
  std::string text = kGood;
  text.replace(text.find("adapter = \"fake\""), 16, "adapter = \"fak\"");
  auto r = parse(text);
  ASSERT_FALSE(r.config);
  EXPECT_THAT(r.errors.front(), AllOf(HasSubstr("no adapter 'fak'"), HasSubstr("fake, streamer")));
}

TEST_F(ConfigTest, ReferencesAreChecked) {
  std::string text = kGood;
  text.replace(text.find("bus = \"line1\""), 13, "bus = \"line2\"");
  auto r = parse(text);
  ASSERT_FALSE(r.config);
  EXPECT_THAT(::testing::PrintToString(r.errors), HasSubstr("no [[bus]] named 'line2'"));
}

TEST_F(ConfigTest, DuplicatesAreRefused) {
  const std::string text = std::string(kGood) +
                           "\n[[device]]\nname = \"washer\"\nbus = \"line1\"\nadapter = \"fake\"\n"
                           "unit_id = 3\naddress = 5\n";
  auto r = parse(text);
  ASSERT_FALSE(r.config);
  const auto all = ::testing::PrintToString(r.errors);
  EXPECT_THAT(all, HasSubstr("declared twice"));
  EXPECT_THAT(all, HasSubstr("unit 3 is already device 'washer'"));
  EXPECT_THAT(all, HasSubstr("address 5 is already device 'washer'"));
}

TEST_F(ConfigTest, AStreamingDeviceMustBeAloneOnItsBus) {
  const std::string text = std::string(kGood) +
                           "\n[[device]]\nname = \"fdc\"\nbus = \"line1\"\nadapter = \"streamer\"\n"
                           "unit_id = 4\n";
  auto r = parse(text);
  ASSERT_FALSE(r.config);
  EXPECT_THAT(::testing::PrintToString(r.errors), HasSubstr("must be alone on its bus"));
}

TEST_F(ConfigTest, MixedAdaptersNeedExplicitLineSettings) {
  const std::string text = R"(
[[bus]]
name = "b"
port = "/dev/ttyS0"
[[device]]
name = "a"
bus = "b"
adapter = "fake"
unit_id = 1
[[device]]
name = "s"
bus = "b"
adapter = "streamer"
unit_id = 2
)";
  auto r = parse(text);
  ASSERT_FALSE(r.config);
  EXPECT_THAT(::testing::PrintToString(r.errors), HasSubstr("set baud, parity"));
}

TEST_F(ConfigTest, SyntaxErrorNamesTheLine) {
  EXPECT_THAT(only_error("[server]\nlisten = \"x:1\"\nmax_clients = = 3\n"),
              HasSubstr("gw.toml:3:"));
}

// In a long file `device[2]` alone is hard to find: every message about a key of a [[device]] or
// [[bus]] table names the table by its `name` beside the key (when the name is a valid one).
TEST_F(ConfigTest, ErrorsNameTheDeviceAndTheBusByTheirNames) {
  std::string text = kGood;
  text.replace(text.find("unit_id = 3"), 11, "unit_id = 248");
  text.replace(text.find("poll_ms = 250"), 13, "poll_ms = 250\npol_ms = 5");
  text.replace(text.find("count = 9"), 9, "count = \"9\"");
  text.replace(text.find("port = \"/dev/ttyUSB0\""), 21, "port = \"/dev/ttyUSB0\"\nbaud = -1");
  const auto r = parse(text);
  const std::string all = ::testing::PrintToString(r.errors);
  EXPECT_EQ(r.errors.size(), 4u) << all;
  EXPECT_THAT(all, HasSubstr("gw.toml:15: device[0].unit_id (device 'washer'): must be in 1..247 "
                             "(got 248)"));
  EXPECT_THAT(all, HasSubstr("gw.toml:18: device[0].pol_ms (device 'washer'): unknown key"));
  EXPECT_THAT(all, HasSubstr("device[0].options.count (device 'washer'): must be an integer"));
  EXPECT_THAT(all, HasSubstr("gw.toml:9: bus[0].baud (bus 'line1'): "));
  // A name that is not a valid one is not repeated (it could be anything): the index alone.
  text = kGood;
  text.replace(text.find("name = \"washer\""), 15, "name = \"wa sher\"");
  text.replace(text.find("unit_id = 3"), 11, "unit_id = 0");
  const std::string bad_name = ::testing::PrintToString(parse(text).errors);
  EXPECT_THAT(bad_name, HasSubstr("device[0].unit_id: must be in 1..247"));
  EXPECT_THAT(bad_name, Not(HasSubstr("wa sher")));
}

// toml++ sees a string left open as a control character (the line break) inside it, or as the
// end of the file on the last line: the error says what most likely happened beside its words.
TEST_F(ConfigTest, AnUnclosedStringIsSaidToBeOne) {
  std::string text = kGood;
  text.replace(text.find("port = \"/dev/ttyUSB0\""), 21, "port = \"/dev/ttyUSB0");
  EXPECT_THAT(only_error(text),
              AllOf(HasSubstr("gw.toml:8: "), HasSubstr("explicitly prohibited"),
                    HasSubstr("(most likely a string left open: its closing \" is missing)")));
  EXPECT_THAT(only_error("[server]\nlisten = '127.0.0.1:1502\n"),
              AllOf(HasSubstr("gw.toml:2: "),
                    HasSubstr("(most likely a string left open: its closing ' is missing)")));
  EXPECT_THAT(only_error("[server]\nlisten = \"127.0.0.1:1502"),
              AllOf(HasSubstr("end-of-file"), HasSubstr("closing \" is missing")));
  // A control character inside a closed string is just that: no guess.
  const std::string ctrl = only_error("[server]\nlisten = \"127.0\x01.0.1:1502\"\n");
  EXPECT_THAT(ctrl, HasSubstr("explicitly prohibited"));
  EXPECT_THAT(ctrl, Not(HasSubstr("left open")));
  // Nor on another line's error.
  EXPECT_THAT(only_error("[server]\nmax_clients = = 3\n"), Not(HasSubstr("left open")));
}

TEST_F(ConfigTest, EmptyFileSaysThereIsNothingToServe) {
  EXPECT_THAT(only_error(""), HasSubstr("no [[device]]"));
}

TEST_F(ConfigTest, BadListenAndBaudAreExplained) {
  std::string text = kGood;
  text.replace(text.find("127.0.0.1:1502"), 14, "127.0.0.1");
  EXPECT_THAT(only_error(text), AllOf(HasSubstr("gw.toml:3:"), HasSubstr("host:port")));
  text = kGood;
  text.replace(text.find("port = \"/dev/ttyUSB0\""), 21, "port = \"/dev/ttyUSB0\"\nbaud = 9601");
  EXPECT_THAT(only_error(text), HasSubstr("not a standard rate"));
}

TEST_F(ConfigTest, MissingFileIsReported) {
  auto r = load_config("/nonexistent/drivegate.toml", plugins_);
  ASSERT_FALSE(r.config);
  EXPECT_THAT(r.errors.front(), HasSubstr("/nonexistent/drivegate.toml: cannot open"));
}

// The configuration file must be a regular file of a sane size; a FIFO, a device or a
// directory is refused at once (never read, never waited on), with what it is.
TEST_F(ConfigTest, TheFileMustBeARegularFile) {
  char tmpl[] = "/tmp/drivegate-config-XXXXXX";
  ASSERT_NE(::mkdtemp(tmpl), nullptr);
  const std::filesystem::path dir = tmpl;
  const auto fifo = dir / "drivegate.toml";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const auto asked = std::chrono::steady_clock::now();
  auto r = load_config(fifo, plugins_);
  EXPECT_LT(std::chrono::steady_clock::now() - asked, std::chrono::seconds(2));
  ASSERT_FALSE(r.config);
  EXPECT_THAT(r.errors.front(), HasSubstr("drivegate.toml: a FIFO, not a regular file"));
  r = load_config("/dev/zero", plugins_);
  EXPECT_THAT(r.errors.front(), HasSubstr("/dev/zero: a character device, not a regular file"));
  r = load_config(dir, plugins_);
  EXPECT_THAT(r.errors.front(), HasSubstr("a directory, not a regular file"));
  const auto huge = dir / "huge.toml";
  std::ofstream(huge).put('#');
  std::filesystem::resize_file(huge, 5 * 1024 * 1024);
  r = load_config(huge, plugins_);
  EXPECT_THAT(r.errors.front(), HasSubstr("more than the 4 MiB allowed"));
  std::filesystem::remove_all(dir);
}

// Names go into the journal, the page, metric labels and Sparkplug topics: a newline, a quote or
// a slash in one is refused with the file, line and key.
TEST_F(ConfigTest, NamesAreLettersDigitsAndAFewMarks) {
  for (const char* bad : {R"(line\nX)", R"(wa\"sher)", "-line", "a/b", "a b", "<b>"}) {
    std::string text = kGood;
    text.replace(text.find("name = \"washer\""), 15, std::string("name = \"") + bad + "\"");
    EXPECT_THAT(only_error(text), AllOf(HasSubstr("gw.toml:"), HasSubstr("device[0].name"),
                                        HasSubstr("letters, digits")))
        << bad;
  }
  std::string text = kGood;
  text.replace(text.find("name = \"washer\""), 15, "name = \"" + std::string(65, 'w') + "\"");
  EXPECT_THAT(only_error(text), HasSubstr("1 to 64"));
  text = kGood;
  text.replace(text.find("name = \"line1\""), 14, "name = \"line_1.a-b\"");
  text.replace(text.find("bus = \"line1\""), 13, "bus = \"line_1.a-b\"");
  EXPECT_TRUE(parse(text).config.has_value()) << ::testing::PrintToString(parse(text).errors);
}

TEST_F(ConfigTest, AllErrorsAreReportedAtOnce) {
  std::string text = kGood;
  text.replace(text.find("unit_id = 3"), 11, "unit_id = 0");
  text.replace(text.find("poll_ms = 250"), 13, "poll_ms = 1");
  auto r = parse(text);
  EXPECT_EQ(r.errors.size(), 2u) << ::testing::PrintToString(r.errors);
}

TEST_F(ConfigTest, OptionTextParsingFollowsTheSchema) {
  std::string error;
  EXPECT_EQ(std::get<std::int64_t>(*parse_option_text(test::kFakeOptions[0], "5", error)), 5);
  EXPECT_FALSE(parse_option_text(test::kFakeOptions[0], "12", error));
  EXPECT_THAT(error, HasSubstr("1..10"));
  EXPECT_FALSE(parse_option_text(test::kFakeOptions[0], "4x", error));
  EXPECT_FALSE(parse_option_text(test::kFakeOptions[2], "yes", error));
  const Options d = default_options(test::kFakeAdapter);
  EXPECT_EQ(d.string_list("names"), (std::vector<std::string>{"a", "b"}));
}

// The command line (`drivegate sim --set`) and the schema's defaults read numbers as TOML does:
// decimal, whatever the leading zeros, and nothing else.
TEST_F(ConfigTest, OptionTextIntegersAreDecimalOnly) {
  const OptionSpec& count = test::kFakeOptions[0];  // 1..10
  const auto integer = [](const OptionSpec& spec, std::string_view text) {
    std::string error;
    const auto v = parse_option_text(spec, text, error);
    EXPECT_TRUE(v) << text << ": " << error;
    return v ? std::get<std::int64_t>(*v) : -1;
  };
  const auto refused = [](const OptionSpec& spec, std::string_view text) {
    std::string error;
    EXPECT_FALSE(parse_option_text(spec, text, error)) << text;
    return error;
  };
  EXPECT_EQ(integer(count, "010"), 10);
  EXPECT_EQ(integer(count, "07"), 7);
  EXPECT_EQ(refused(count, "0x10"), "count: '0x10' is not a decimal integer");
  for (const char* bad : {"0x5", "0X5", "+5", " 5", "5 ", "", "-", "5.0", "1e1", "0b1"}) {
    EXPECT_THAT(refused(count, bad), HasSubstr("is not a decimal integer")) << bad;
  }
  const OptionSpec any{"offset", OptionType::integer, "0", "unbounded"};
  EXPECT_EQ(integer(any, "-42"), -42);
  EXPECT_EQ(integer(any, "-9223372036854775808"), std::numeric_limits<std::int64_t>::min());
  EXPECT_EQ(integer(any, "9223372036854775807"), std::numeric_limits<std::int64_t>::max());
  EXPECT_THAT(refused(any, "9223372036854775808"), HasSubstr("out of the 64-bit integer range"));
  EXPECT_THAT(refused(any, "-9223372036854775809"), HasSubstr("out of the 64-bit integer range"));
  EXPECT_THAT(refused(any, "--1"), HasSubstr("is not a decimal integer"));
  // A range says its bounds as written, not in a float's six digits (nidec-washer's
  // accel_time_ms once read "must be in 0..6.5535e+06").
  const OptionSpec wide{"accel_time_ms", OptionType::integer, "0", "two bytes of 100 ms", 0,
                        6553500};
  EXPECT_THAT(refused(wide, "-5"), HasSubstr("must be in 0..6553500 (got -5)"));
}

TEST_F(ConfigTest, OptionTextRealsAreFiniteDecimalOnly) {
  const OptionSpec& ratio = test::kFakeOptions[1];  // 0.0..1.0
  std::string error;
  for (const auto& [text, value] : std::vector<std::pair<const char*, double>>{
           {"0.25", 0.25}, {"1", 1.0}, {"0", 0.0}, {"2.5e-1", 0.25}, {"0.50", 0.5}}) {
    const auto v = parse_option_text(ratio, text, error);
    ASSERT_TRUE(v) << text << ": " << error;
    EXPECT_DOUBLE_EQ(std::get<double>(*v), value) << text;
  }
  // std::stod took all of these: hex floats, infinities and NaNs, a '+', leading blanks.
  for (const char* bad :
       {"0x1p-2", "inf", "-inf", "nan", "infinity", "+0.5", " 0.5", "0.5x", "", "1e400"}) {
    EXPECT_FALSE(parse_option_text(ratio, bad, error)) << bad;
    EXPECT_THAT(error, HasSubstr("is not a finite decimal number")) << bad;
  }
  EXPECT_FALSE(parse_option_text(ratio, "1.5", error));
  EXPECT_THAT(error, HasSubstr("must be in 0..1"));
}

// Devices on one bus share its echo as they share its framing.
constexpr const char* kFakeAndQuiet = R"(
[[bus]]
name = "b"
port = "/dev/ttyS0"
[[device]]
name = "a"
bus = "b"
adapter = "fake"
unit_id = 1
[[device]]
name = "q"
bus = "b"
adapter = "quiet"
unit_id = 2
)";

TEST_F(ConfigTest, AdaptersDisagreeingOnEchoNeedAnExplicitEcho) {
  plugins_.add(test::kFakeQuiet);
  EXPECT_THAT(only_error(kFakeAndQuiet),
              AllOf(HasSubstr("gw.toml:2: bus 'b': its devices' adapters disagree on echo"),
                    HasSubstr("'fake' echo = true, 'quiet' echo = false"),
                    HasSubstr("set echo explicitly")));
  // Giving the framing is not enough: echo is a setting of its own.
  std::string text = kFakeAndQuiet;
  text.replace(text.find("port = \"/dev/ttyS0\""), 19,
               "port = \"/dev/ttyS0\"\nbaud = 4800\nparity = \"odd\"\ndata_bits = 8\n"
               "stop_bits = 1");
  EXPECT_THAT(only_error(text), HasSubstr("disagree on echo"));
}

TEST_F(ConfigTest, AnExplicitEchoAppliesToEveryDeviceOnTheBus) {
  plugins_.add(test::kFakeQuiet);
  for (const bool echo : {false, true}) {
    std::string text = kFakeAndQuiet;
    text.replace(text.find("port = \"/dev/ttyS0\""), 19,
                 std::string("port = \"/dev/ttyS0\"\necho = ") + (echo ? "true" : "false"));
    auto r = parse(text);
    ASSERT_TRUE(r.config) << ::testing::PrintToString(r.errors);
    EXPECT_EQ(r.config->buses[0].echo, echo);
    EXPECT_EQ(r.config->buses[0].baud, 4800u);
  }
}

TEST_F(ConfigTest, ABusBehindASerialDeviceServer) {
  std::string text = kGood;
  text.replace(text.find("port = \"/dev/ttyUSB0\""), 21,
               "port = \"rfc2217://10.1.5.20:4001\"\nnetwork_delay_ms = 20");
  auto r = parse(text);
  ASSERT_TRUE(r.config) << ::testing::PrintToString(r.errors);
  EXPECT_EQ(r.config->buses[0].port, "rfc2217://10.1.5.20:4001");
  EXPECT_EQ(r.config->buses[0].network_delay, Millis(20));
  text = kGood;
  text.replace(text.find("port = \"/dev/ttyUSB0\""), 21, "port = \"tcp://10.1.5.20\"");
  EXPECT_THAT(only_error(text), AllOf(HasSubstr("gw.toml:8: bus[0].port (bus 'line1'):"),
                                      HasSubstr("tcp://host:port")));
  text = kGood;
  text.replace(text.find("port = \"/dev/ttyUSB0\""), 21,
               "port = \"tcp://10.1.5.20:4001\"\nrs485 = true");
  EXPECT_THAT(only_error(text), AllOf(HasSubstr("bus[0].rs485"), HasSubstr("local serial port")));
  text = kGood;
  text.replace(text.find("port = \"/dev/ttyUSB0\""), 21,
               "port = \"tcp://10.1.5.20:4001\"\nnetwork_delay_ms = 20000");
  EXPECT_THAT(only_error(text), AllOf(HasSubstr("network_delay_ms"), HasSubstr("0..10000")));
}

}  // namespace
}  // namespace drivegate
