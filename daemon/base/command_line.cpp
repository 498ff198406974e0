#include "base/command_line.h"

#include <getopt.h>

#include <algorithm>
#include <cstring>
#include <iostream>
#include <stdexcept>

namespace drivegate {
namespace {

// The help is read in a terminal: every line fits 80 columns.
constexpr std::size_t kWidth = 79;
// The options' column; a longer "-x, --name ARG" puts its help on the next line.
constexpr std::size_t kHelpColumn = 28;
// getopt_long's value for an option without a short form: past every char, so never one.
constexpr int kLongOnly = 256;

std::string dashed(const Option& o) {
  return std::string("--") + o.long_name;
}

// "  -c, --config FILE" or "      --listen HOST:PORT".
std::string left_column(const Option& o) {
  std::string out = o.short_name != 0 ? std::string("  -") + o.short_name + ", " : "      ";
  out += dashed(o);
  if (o.arg != nullptr) out += std::string(" ") + o.arg;
  return out;
}

// `text` wrapped at spaces to kWidth, each line after the first indented by `indent` columns;
// `first` is how many columns the first line already has.
std::string wrapped(std::string_view text, std::size_t first, std::size_t indent) {
  std::string out;
  std::size_t column = first;
  bool line_start = true;
  while (!text.empty()) {
    const auto space = text.find(' ');
    const std::string_view word = text.substr(0, space);
    text = space == std::string_view::npos ? std::string_view() : text.substr(space + 1);
    if (word.empty()) continue;
    if (!line_start && column + 1 + word.size() > kWidth) {
      out += "\n" + std::string(indent, ' ');
      column = indent;
      line_start = true;
    }
    if (!line_start) {
      out += ' ';
      ++column;
    }
    out += word;
    column += word.size();
    line_start = false;
  }
  return out;
}

}  // namespace

void ParsedArgs::check_known(std::string_view long_name) const {
  for (const Option& o : table_) {
    if (long_name == o.long_name) return;
  }
  throw std::logic_error("the option table has no --" + std::string(long_name));
}

bool ParsedArgs::has(std::string_view long_name) const {
  check_known(long_name);
  return std::any_of(given_.begin(), given_.end(),
                     [&](const Given& g) { return long_name == g.option->long_name; });
}

std::optional<std::string> ParsedArgs::value(std::string_view long_name) const {
  check_known(long_name);
  const auto g = std::find_if(given_.rbegin(), given_.rend(),
                              [&](const Given& x) { return long_name == x.option->long_name; });
  if (g == given_.rend()) return std::nullopt;
  return g->value;
}

std::vector<std::string> ParsedArgs::values(std::string_view long_name) const {
  check_known(long_name);
  std::vector<std::string> out;
  for (const Given& g : given_) {
    if (long_name == g.option->long_name) out.push_back(g.value);
  }
  return out;
}

std::optional<std::string_view> ParsedArgs::last_of(
    std::initializer_list<std::string_view> long_names) const {
  for (const auto name : long_names) check_known(name);
  const auto g = std::find_if(given_.rbegin(), given_.rend(), [&](const Given& x) {
    return std::find(long_names.begin(), long_names.end(), x.option->long_name) != long_names.end();
  });
  if (g == given_.rend()) return std::nullopt;
  return std::string_view(g->option->long_name);
}

CommandLine::CommandLine(std::string program, std::span<const Option> options,
                         std::vector<std::string> synopsis, std::string about)
    : program_(std::move(program)),
      options_(options),
      synopsis_(std::move(synopsis)),
      about_(std::move(about)) {
  for (std::size_t i = 0; i < options_.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      if (std::strcmp(options_[i].long_name, options_[j].long_name) == 0 ||
          (options_[i].short_name != 0 && options_[i].short_name == options_[j].short_name)) {
        throw std::logic_error(program_ + ": options " + dashed(options_[j]) + " and " +
                               dashed(options_[i]) + " share a name");
      }
    }
  }
}

ParsedArgs CommandLine::parse(std::span<const std::string> args, OperandOrder order) const {
  ParsedArgs parsed;
  parsed.table_ = options_;

  // getopt_long's tables. '-' returns operands in place (code 1), so options may follow them
  // whatever POSIXLY_CORRECT says; '+' stops at the first operand.
  std::string shorts = order == OperandOrder::anywhere ? "-" : "+";
  std::vector<option> longs;
  for (std::size_t i = 0; i < options_.size(); ++i) {
    const Option& o = options_[i];
    const int has_arg = o.arg != nullptr ? required_argument : no_argument;
    const int val = o.short_name != 0 ? o.short_name : kLongOnly + static_cast<int>(i);
    longs.push_back({o.long_name, has_arg, nullptr, val});
    if (o.short_name != 0) {
      shorts += o.short_name;
      if (o.arg != nullptr) shorts += ':';
    }
  }
  longs.push_back({nullptr, 0, nullptr, 0});
  const auto by_val = [&](int val) -> const Option* {
    for (std::size_t i = 0; i < options_.size(); ++i) {
      const Option& o = options_[i];
      if (val == (o.short_name != 0 ? o.short_name : kLongOnly + static_cast<int>(i))) return &o;
    }
    return nullptr;
  };

  // getopt_long permutes its argv: it gets copies, never the caller's strings.
  std::vector<std::string> storage;
  storage.reserve(args.size() + 1);
  storage.push_back(program_);
  storage.insert(storage.end(), args.begin(), args.end());
  std::vector<char*> argv;
  argv.reserve(storage.size() + 1);
  for (auto& s : storage) argv.push_back(s.data());
  argv.push_back(nullptr);
  const int argc = static_cast<int>(storage.size());

  // The messages are ours (one line, naming the option); getopt's state starts afresh (0), so
  // a second parse in one process reads its own argv.
  opterr = 0;
  optind = 0;
  while (true) {
    const int c = getopt_long(argc, argv.data(), shorts.c_str(), longs.data(), nullptr);
    if (c == -1) break;
    if (c == 1) {
      parsed.operands.emplace_back(optarg);
      continue;
    }
    if (c == '?') {
      // What was typed: the word getopt has just passed over.
      const std::string_view word = optind > 0 && optind <= argc ? argv[optind - 1] : "";
      const Option* known = optopt != 0 ? by_val(optopt) : nullptr;
      const bool typed_long = word.starts_with("--");
      if (known != nullptr) {
        const std::string name = typed_long || known->short_name == 0
                                     ? dashed(*known)
                                     : std::string("-") + known->short_name;
        parsed.error = known->arg != nullptr
                           ? "option '" + name + "' needs a value (" + known->arg + ")"
                           : "option '" + name + "' takes no value";
      } else if (optopt != 0) {
        parsed.error = std::string("unknown option '-") + static_cast<char>(optopt) + "'";
      } else {
        const std::string name(word.substr(0, word.find('=')));
        // getopt_long takes any unambiguous abbreviation; an ambiguous one names its candidates.
        std::string candidates;
        for (const Option& o : options_) {
          if (dashed(o).starts_with(name) && name.size() > 2) {
            candidates += (candidates.empty() ? "" : ", ") + dashed(o);
          }
        }
        parsed.error = candidates.empty() ? "unknown option '" + name + "'"
                                          : "ambiguous option '" + name + "' (" + candidates + ")";
      }
      return parsed;
    }
    const Option* o = by_val(c);
    if (o == nullptr) {  // cannot happen: getopt returns only what the tables hold
      parsed.error = "unexpected option code " + std::to_string(c);
      return parsed;
    }
    parsed.given_.push_back({o, o->arg != nullptr && optarg != nullptr ? optarg : ""});
  }
  for (int i = optind; i < argc; ++i) parsed.operands.emplace_back(argv[i]);
  return parsed;
}

std::string CommandLine::usage() const {
  std::string out;
  for (std::size_t i = 0; i < synopsis_.size(); ++i) {
    out += (i == 0 ? "usage: " : "       ") + program_ + (synopsis_[i].empty() ? "" : " ") +
           synopsis_[i] + "\n";
  }
  if (options_.empty()) return out;
  out += "\noptions:\n";
  for (const Option& o : options_) {
    std::string line = left_column(o);
    if (line.size() + 2 > kHelpColumn) {
      line += "\n" + std::string(kHelpColumn, ' ');
    } else {
      line.resize(kHelpColumn, ' ');
    }
    out += line + wrapped(o.help, kHelpColumn, kHelpColumn) + "\n";
  }
  return out;
}

std::string CommandLine::help() const {
  std::string out = usage();
  if (about_.empty()) return out;
  // The about text goes between the usage lines and the options, its prose wrapped like the
  // options' help; a paragraph with an indented line (a list) is kept as it is written.
  std::string about = "\n";
  std::string_view rest = about_;
  while (!rest.empty()) {
    const auto end = rest.find("\n\n");
    std::string_view paragraph = rest.substr(0, end);
    rest = end == std::string_view::npos ? std::string_view() : rest.substr(end + 2);
    while (paragraph.ends_with('\n')) paragraph.remove_suffix(1);
    if (about.size() > 1) about += "\n";
    if (paragraph.find("\n  ") != std::string_view::npos || paragraph.starts_with("  ")) {
      about += std::string(paragraph) + "\n";
      continue;
    }
    std::string joined(paragraph);
    std::replace(joined.begin(), joined.end(), '\n', ' ');
    about += wrapped(joined, 0, 0) + "\n";
  }
  const auto options_at = out.find("\noptions:\n");
  if (options_at == std::string::npos) return out + about;
  return out.insert(options_at, about);
}

int CommandLine::usage_error(std::string_view what) const {
  std::cerr << program_ << ": " << what << "\n" << usage();
  return 2;
}

}  // namespace drivegate
