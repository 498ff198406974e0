// drivegated's command line (daemon/app/daemon_args.h), and drivegated(8), which must document
// exactly the options of its table.
#include "app/daemon_args.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>

namespace drivegate {
namespace {

using ::testing::HasSubstr;

std::variant<DaemonArgs, std::string> parse(std::vector<std::string> args) {
  return parse_daemon_args(args);
}

TEST(DaemonArgs, ConfigInEveryFormAndTheShortOptions) {
  for (const auto& args : std::vector<std::vector<std::string>>{
           {"--config", "/etc/x.toml"}, {"--config=/etc/x.toml"}, {"-c", "/etc/x.toml"}}) {
    const auto r = parse(args);
    ASSERT_TRUE(std::holds_alternative<DaemonArgs>(r)) << std::get<std::string>(r);
    EXPECT_EQ(std::get<DaemonArgs>(r).action, DaemonAction::run);
    EXPECT_EQ(std::get<DaemonArgs>(r).options.config, "/etc/x.toml");
  }
  const auto r =
      parse({"-c", "x.toml", "-l", "debug", "-p", "/plugins", "--listen=127.0.0.1:1502"});
  ASSERT_TRUE(std::holds_alternative<DaemonArgs>(r)) << std::get<std::string>(r);
  const auto& a = std::get<DaemonArgs>(r);
  EXPECT_EQ(a.log_level, spdlog::level::debug);
  EXPECT_EQ(a.options.plugin_dir, "/plugins");
  ASSERT_TRUE(a.options.listen);
  EXPECT_EQ(a.options.listen->port, 1502);
}

TEST(DaemonArgs, CheckHelpVersion) {
  const auto check = parse({"--check-config=/etc/x.toml", "-p", "/plugins"});
  ASSERT_TRUE(std::holds_alternative<DaemonArgs>(check));
  EXPECT_EQ(std::get<DaemonArgs>(check).action, DaemonAction::check_config);
  EXPECT_EQ(std::get<DaemonArgs>(check).check, "/etc/x.toml");
  EXPECT_EQ(std::get<DaemonArgs>(parse({"-h"})).action, DaemonAction::help);
  EXPECT_EQ(std::get<DaemonArgs>(parse({"--help"})).action, DaemonAction::help);
  EXPECT_EQ(std::get<DaemonArgs>(parse({"-V"})).action, DaemonAction::version);
  EXPECT_EQ(std::get<DaemonArgs>(parse({"--version"})).action, DaemonAction::version);
}

TEST(DaemonArgs, StateDirFromTheOptionElseSystemdsStateDirectory) {
  const auto r = parse({"-c", "x.toml", "--state-dir", "/var/lib/dg"});
  ASSERT_TRUE(std::holds_alternative<DaemonArgs>(r)) << std::get<std::string>(r);
  EXPECT_EQ(std::get<DaemonArgs>(r).options.state_dir, "/var/lib/dg");
  EXPECT_EQ(std::get<DaemonArgs>(parse({"-c", "x.toml"})).options.state_dir, "");
  EXPECT_THAT(std::get<std::string>(parse({"-c", "x", "--state-dir="})),
              HasSubstr("--state-dir needs a directory"));
  // The option wins; else $STATE_DIRECTORY, the first of its list (StateDirectory= a b).
  EXPECT_EQ(resolve_state_dir("/opt/s", "/var/lib/drivegate"), "/opt/s");
  EXPECT_EQ(resolve_state_dir({}, "/var/lib/drivegate"), "/var/lib/drivegate");
  EXPECT_EQ(resolve_state_dir({}, "/var/lib/a:/var/lib/b"), "/var/lib/a");
  EXPECT_EQ(resolve_state_dir({}, nullptr), "");
}

TEST(DaemonArgs, MistakesNameWhatIsWrong) {
  EXPECT_EQ(std::get<std::string>(parse({"--frobnicate"})), "unknown option '--frobnicate'");
  EXPECT_EQ(std::get<std::string>(parse({"-c"})), "option '-c' needs a value (FILE)");
  EXPECT_EQ(std::get<std::string>(parse({})), "--config FILE is required");
  EXPECT_EQ(std::get<std::string>(parse({"-c", "x", "stray"})), "unexpected argument 'stray'");
  EXPECT_THAT(std::get<std::string>(parse({"-c", "x", "--listen", "nowhere"})),
              HasSubstr("--listen needs HOST:PORT"));
  EXPECT_THAT(std::get<std::string>(parse({"-c", "x", "-l", "loud"})), HasSubstr("not 'loud'"));
}

TEST(DaemonArgs, HelpListsEveryOptionOfTheTable) {
  const std::string help = daemon_command_line().help();
  for (const Option& o : daemon_option_table()) {
    EXPECT_THAT(help, HasSubstr(std::string("--") + o.long_name));
    if (o.short_name != 0) {
      EXPECT_THAT(help, HasSubstr(std::string("-") + o.short_name + ", --" + o.long_name));
    }
  }
}

// troff writes a hyphen as \- : "--check-config" is "\-\-check\-config" in the page.
std::string troff(std::string_view option) {
  std::string out;
  for (const char c : option) out += c == '-' ? std::string("\\-") : std::string(1, c);
  return out;
}

std::string section(const std::string& page, const std::string& name) {
  const auto start = page.find(".SH " + name + "\n");
  if (start == std::string::npos) return {};
  const auto end = page.find("\n.SH ", start + 1);
  return page.substr(start, end == std::string::npos ? std::string::npos : end - start);
}

// drivegated(8) documents exactly the options the daemon takes: each of the table in OPTIONS
// (short form beside the long one), and no other in SYNOPSIS or OPTIONS.
TEST(DaemonArgs, TheManPageDocumentsExactlyTheTable) {
  std::ifstream in(std::filesystem::path(DRIVEGATE_SOURCE_DIR) / "packaging/man/drivegated.8");
  ASSERT_TRUE(in) << "packaging/man/drivegated.8";
  std::stringstream text;
  text << in.rdbuf();
  const std::string page = text.str();
  const std::string options = section(page, "OPTIONS");
  const std::string synopsis = section(page, "SYNOPSIS");
  ASSERT_FALSE(options.empty());
  ASSERT_FALSE(synopsis.empty());
  std::set<std::string> table;
  for (const Option& o : daemon_option_table()) {
    const std::string long_form = troff(std::string("--") + o.long_name);
    table.insert(long_form);
    EXPECT_THAT(options, HasSubstr(long_form)) << "drivegated(8) OPTIONS lacks --" << o.long_name;
    if (o.short_name != 0) {
      const std::string both = troff(std::string("-") + o.short_name) + " \", \" " + long_form;
      EXPECT_THAT(options, HasSubstr(both))
          << "drivegated(8) OPTIONS lacks -" << o.short_name << " beside --" << o.long_name;
    }
  }
  const std::regex long_option(R"(\\-\\-[a-z]+(\\-[a-z]+)*)");
  for (const std::string* part : {&options, &synopsis}) {
    for (std::sregex_iterator m(part->begin(), part->end(), long_option), end; m != end; ++m) {
      EXPECT_TRUE(table.contains(m->str()))
          << "drivegated(8) documents " << m->str() << ", which drivegated does not take";
    }
  }
}

}  // namespace
}  // namespace drivegate
