// Command lines from a table of options (daemon/base/command_line.h): every GNU form parses, the
// help lists the table, and each mistake is one line naming the option.
#include "base/command_line.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <stdexcept>

namespace drivegate {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

constexpr Option kOptions[] = {
    {"config", 'c', "FILE", "the configuration"},
    {"check-config", 0, "FILE", "check it"},
    {"address", 'a', "N", "an address, repeatable"},
    {"echo", 0, nullptr, "echo"},
    {"no-echo", 0, nullptr, "do not echo"},
    {"help", 'h', nullptr, "print this help and exit"},
};

CommandLine cli() {
  return CommandLine("prog", kOptions, {"-c FILE [OPTION]... ARG..."}, "What prog does.");
}

ParsedArgs parse(std::vector<std::string> args, OperandOrder order = OperandOrder::anywhere) {
  return cli().parse(args, order);
}

TEST(CommandLine, EveryFormOfAValue) {
  for (const auto& args : std::vector<std::vector<std::string>>{
           {"--config", "a.toml"}, {"--config=a.toml"}, {"-c", "a.toml"}, {"-ca.toml"}}) {
    const auto p = parse(args);
    ASSERT_FALSE(p.error) << *p.error;
    EXPECT_EQ(p.value("config"), "a.toml") << args[0];
  }
}

TEST(CommandLine, OperandsAnywhereRepeatsInOrderAndTheLastFlagWins) {
  const auto p = parse({"x", "-a", "1", "y", "--address=2", "--echo", "--no-echo", "--", "-z"});
  ASSERT_FALSE(p.error) << *p.error;
  EXPECT_THAT(p.operands, ElementsAre("x", "y", "-z"));
  EXPECT_THAT(p.values("address"), ElementsAre("1", "2"));
  EXPECT_EQ(p.value("address"), "2");
  EXPECT_EQ(p.last_of({"echo", "no-echo"}), "no-echo");
  EXPECT_FALSE(p.has("config"));
  EXPECT_FALSE(p.value("config"));
}

// A program with subcommands leaves everything from the command on to the command.
TEST(CommandLine, OptionsFirstStopsAtTheFirstOperand) {
  const auto p = parse({"-h", "regmap", "--config", "x", "-h"}, OperandOrder::options_first);
  ASSERT_FALSE(p.error) << *p.error;
  EXPECT_TRUE(p.has("help"));
  EXPECT_THAT(p.operands, ElementsAre("regmap", "--config", "x", "-h"));
}

TEST(CommandLine, EachMistakeIsOneLineNamingTheOption) {
  EXPECT_EQ(parse({"--frobnicate"}).error, "unknown option '--frobnicate'");
  EXPECT_EQ(parse({"--frobnicate=3"}).error, "unknown option '--frobnicate'");
  EXPECT_EQ(parse({"-x"}).error, "unknown option '-x'");
  EXPECT_EQ(parse({"--config"}).error, "option '--config' needs a value (FILE)");
  EXPECT_EQ(parse({"x", "-c"}).error, "option '-c' needs a value (FILE)");
  EXPECT_EQ(parse({"--check-config"}).error, "option '--check-config' needs a value (FILE)");
  EXPECT_EQ(parse({"--echo=1"}).error, "option '--echo' takes no value");
  EXPECT_EQ(parse({"--c", "x"}).error, "ambiguous option '--c' (--config, --check-config)");
  // getopt_long takes an unambiguous abbreviation.
  EXPECT_EQ(parse({"--conf", "x"}).value("config"), "x");
}

// A name that is not in the table is a bug in the program, not a user's mistake.
TEST(CommandLine, AskingForAnOptionNotInTheTableThrows) {
  const auto p = parse({});
  EXPECT_THROW((void)p.has("confg"), std::logic_error);
  EXPECT_THROW((void)p.value("confg"), std::logic_error);
  constexpr Option twice[] = {{"a", 'x', nullptr, ""}, {"b", 'x', nullptr, ""}};
  EXPECT_THROW(CommandLine("p", twice, {}, ""), std::logic_error);
}

// A second parse in one process reads its own arguments (getopt's state is reset).
TEST(CommandLine, ParsesAgain) {
  EXPECT_EQ(parse({"-c", "one", "a"}).value("config"), "one");
  const auto again = parse({"b", "-c", "two"});
  EXPECT_EQ(again.value("config"), "two");
  EXPECT_THAT(again.operands, ElementsAre("b"));
}

TEST(CommandLine, HelpListsTheWholeTableUsageLeavesTheProseOut) {
  const std::string help = cli().help();
  EXPECT_THAT(help, HasSubstr("usage: prog -c FILE [OPTION]... ARG...\n"));
  EXPECT_THAT(help, HasSubstr("\nWhat prog does.\n"));
  EXPECT_THAT(help, HasSubstr("\n  -c, --config FILE         the configuration\n"));
  EXPECT_THAT(help, HasSubstr("\n      --check-config FILE   check it\n"));
  EXPECT_THAT(help, HasSubstr("\n      --no-echo             do not echo\n"));
  for (const Option& o : kOptions) EXPECT_THAT(help, HasSubstr(std::string("--") + o.long_name));
  const std::string usage = cli().usage();
  EXPECT_THAT(usage, HasSubstr("  -h, --help"));
  EXPECT_THAT(usage, ::testing::Not(HasSubstr("What prog does.")));
}

TEST(CommandLine, LongHelpIsWrappedToEightyColumns) {
  constexpr Option wordy[] = {
      {"long-winded-option-name", 'l', "SOMETHING",
       "a help text long enough to need more than one line of the terminal, and then some more "
       "words to be sure of it"}};
  const std::string help = CommandLine("p", wordy, {""}, "").help();
  std::size_t start = 0;
  while (start < help.size()) {
    const auto nl = help.find('\n', start);
    EXPECT_LE(nl - start, 79u) << help.substr(start, nl - start);
    start = nl + 1;
  }
  EXPECT_THAT(help,
              HasSubstr("  -l, --long-winded-option-name SOMETHING\n                            a "
                        "help text"));
}

// The prose of the about text is wrapped too; a paragraph with indented lines is a list, kept.
TEST(CommandLine, AboutProseIsWrappedListsAreKept) {
  const std::string help =
      CommandLine("p", kOptions, {""},
                  "One paragraph written on lines of any length, which the help wraps at the "
                  "terminal's width,\nso that whoever writes it need not count its columns.\n"
                  "\n"
                  "list:\n"
                  "  a    the first item of a list, kept on its line whatever it looks like ok\n")
          .help();
  EXPECT_THAT(help, HasSubstr("\nOne paragraph written on lines of any length, which the help "
                              "wraps at the\nterminal's width, so that whoever writes it need "
                              "not count its columns.\n"));
  EXPECT_THAT(help, HasSubstr("\n\nlist:\n  a    the first item of a list, kept on its line "
                              "whatever it looks like ok\n"));
  EXPECT_THAT(help, HasSubstr("ok\n\noptions:\n"));
}

}  // namespace
}  // namespace drivegate
