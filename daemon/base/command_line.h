// A program's command line from one table of options: getopt_long parses it (GNU style: --name
// VALUE, --name=VALUE, -n VALUE, -nVALUE, operands anywhere, `--` ends the options) and the help
// text is printed from the very same table, so what is accepted and what is documented cannot
// drift apart. The man pages list the same options; tests hold them to the tables.
#pragma once

#include <cstdint>
#include <initializer_list>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace drivegate {

struct Option {
  const char* long_name;  // without the dashes: "config"
  char short_name;        // 'c'; 0: long form only
  const char* arg;        // the value's name in the help ("FILE"); nullptr: a flag, no value
  const char* help;       // one or two sentences, wrapped to the terminal's 80 columns
};

// Whether options may follow operands. A program with subcommands stops at its first operand
// (the command's name), so the command's own options are left for the command to parse.
enum class OperandOrder : std::uint8_t { anywhere, options_first };

class CommandLine;

// What a command line said, looked up by long name. Asking for a name that is not in the table
// throws std::logic_error: a misspelt name is a bug, and the first run of the program shows it,
// whatever options that run was given.
class ParsedArgs {
 public:
  // Set when the command line is wrong: one line naming the option ("unknown option '--frob'",
  // "option '--config' needs a value (FILE)"). Nothing else is meaningful then.
  std::optional<std::string> error;
  // The operands in the order given; with OperandOrder::options_first, everything from the
  // first operand on.
  std::vector<std::string> operands;

  [[nodiscard]] bool has(std::string_view long_name) const;
  // The value given last (an option given twice: the second wins, as usual).
  [[nodiscard]] std::optional<std::string> value(std::string_view long_name) const;
  // Every value given, in order (repeatable options: `sim --address 1 --address 2`).
  [[nodiscard]] std::vector<std::string> values(std::string_view long_name) const;
  // Of `long_names`, the one given last (`--echo` / `--no-echo`); nullopt when none was.
  [[nodiscard]] std::optional<std::string_view> last_of(
      std::initializer_list<std::string_view> long_names) const;

 private:
  friend class CommandLine;
  struct Given {
    const Option* option;
    std::string value;
  };
  void check_known(std::string_view long_name) const;
  std::span<const Option> table_;
  std::vector<Given> given_;
};

class CommandLine {
 public:
  // `program`: how errors and the help name it ("drivegated", "drivegate regmap"). `synopsis`:
  // the usage lines, without "usage: " and the program's name (operands and which options go
  // together). `about`: paragraphs printed between the usage and the options by help().
  // Throws std::logic_error when two options share a name.
  CommandLine(std::string program, std::span<const Option> options,
              std::vector<std::string> synopsis, std::string about);

  // `args`: what follows the program's (or subcommand's) name.
  [[nodiscard]] ParsedArgs parse(std::span<const std::string> args,
                                 OperandOrder order = OperandOrder::anywhere) const;

  // Usage lines, `about`, then every option of the table: what --help prints on stdout.
  [[nodiscard]] std::string help() const;
  // Usage lines and the options, without `about`: what follows a usage error.
  [[nodiscard]] std::string usage() const;
  // "PROGRAM: WHAT" and the usage on stderr; returns 2, the exit status of a usage error.
  int usage_error(std::string_view what) const;

  [[nodiscard]] std::span<const Option> options() const { return options_; }

 private:
  std::string program_;
  std::span<const Option> options_;
  std::vector<std::string> synopsis_;
  std::string about_;
};

}  // namespace drivegate
