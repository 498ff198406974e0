// drivegate protocol: a protocol description (adapters/framed, docs/protocols.md) checked without
// a line: `check` validates it (every error FILE:LINE: key: what), `decode` reads hex bytes into
// named fields, `encode` makes a message's bytes from field values, `list` names the descriptions
// found, `dissector` prints its data for the Wireshark dissector. The framed adapter's library
// does the work (adapters/framed/inspect.h); this file reads the command line.
#include <filesystem>
#include <iostream>

#include "commands.h"
#include "framed/description_parser.h"
#include "framed/inspect.h"
#include "framed/settings.h"
#include "plugin/adapter_options.h"

namespace drivegate::cli {

namespace {

constexpr Option kProtocolOptions[] = {
    {"request", 0, nullptr, "decode: the bytes are the master's (requests)"},
    {"reply", 0, nullptr, "decode: the bytes are the device's (replies, streams)"},
    {"set", 0, "OPTION=VALUE",
     "encode: the description's option OPTION is VALUE (default: its default)"},
    kHelpOption,
};

constexpr const char* kProtocolAbout =
    "Checks a protocol description (a name, found as a device finds it, or a path):\n"
    "  check        validate it; every error FILE:LINE: key: what\n"
    "  decode HEX   the frames in the bytes, field by field\n"
    "  encode MESSAGE [FIELD=VALUE]...\n"
    "               a message's bytes (the other fields as it sends them)\n"
    "  list         the descriptions found, and where\n"
    "  dissector    its data for the Wireshark dissector (Lua)\n"
    "See docs/protocols.md.";

// The description `what` names, or every error (printed) and nullptr.
std::shared_ptr<const framed::Description> description(const std::string& what) {
  std::string error;
  const auto text = framed::find_description(what, error);
  if (!text) {
    std::cerr << "drivegate protocol: " << error << "\n";
    return nullptr;
  }
  auto parsed = framed::parse_description(text->text, text->source);
  if (const auto* errors = std::get_if<std::vector<std::string>>(&parsed)) {
    for (const auto& e : *errors) std::cerr << e << "\n";
    return nullptr;
  }
  return std::get<std::shared_ptr<const framed::Description>>(std::move(parsed));
}

// The description's options, defaults first, then --set.
std::optional<Options> options_of(const framed::Description& d, const ParsedArgs& parsed,
                                  std::string& error) {
  Options out;
  for (const framed::Option& o : d.options) {
    OptionSpec spec{o.name.c_str(), o.type, o.default_text.c_str(), o.description.c_str(),
                    o.min,          o.max,  o.choices.c_str()};
    auto v = parse_option_text(spec, o.default_text, error);
    if (!v) return std::nullopt;
    out.set(o.name, std::move(*v));
  }
  for (const std::string& s : parsed.values("set")) {
    const auto eq = s.find('=');
    const std::string name = s.substr(0, eq);
    const auto o = std::find_if(d.options.begin(), d.options.end(),
                                [&](const framed::Option& x) { return x.name == name; });
    if (eq == std::string::npos || o == d.options.end()) {
      error = "--set " + s + ": " + d.name + " has no option '" + name + "'";
      return std::nullopt;
    }
    OptionSpec spec{o->name.c_str(), o->type, o->default_text.c_str(), o->description.c_str(),
                    o->min,          o->max,  o->choices.c_str()};
    auto v = parse_option_text(spec, s.substr(eq + 1), error);
    if (!v) {
      error = "--set " + error;
      return std::nullopt;
    }
    out.set(name, std::move(*v));
  }
  return out;
}

}  // namespace

int protocol(std::span<const std::string> args) {
  const CommandLine cli(
      "drivegate protocol", kProtocolOptions,
      {"check NAME|FILE", "decode [--request|--reply] NAME|FILE HEX...",
       "encode [--set OPTION=V]... NAME|FILE MESSAGE [F=V]...", "list", "dissector NAME|FILE"},
      kProtocolAbout);
  int exit_status = 0;
  const auto parsed = parse_command(cli, args, exit_status);
  if (!parsed) return exit_status;
  const auto& ops = parsed->operands;
  if (ops.empty()) return cli.usage_error("which of check, decode, encode, list, dissector?");
  const std::string& verb = ops[0];
  if (verb == "list") {
    for (const char* dir : framed::kProtocolDirs) {
      std::error_code ec;
      for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
        if (e.path().extension() == ".toml")
          std::cout << e.path().stem().string() << "\t" << e.path().string() << "\n";
      }
    }
    for (const auto name : framed::shipped_names()) std::cout << name << "\tshipped\n";
    return 0;
  }
  if (verb != "check" && verb != "decode" && verb != "encode" && verb != "dissector") {
    return cli.usage_error("no such use '" + verb + "' (check, decode, encode, list, dissector)");
  }
  if (ops.size() < 2) return cli.usage_error(verb + " needs a description: a name or a path");
  const auto d = description(ops[1]);
  if (!d) return 1;
  if (verb == "check") {
    if (ops.size() != 2) return cli.usage_error("check takes one description");
    std::cout << ops[1] << ": OK (" << d->name << ": " << d->messages.size() << " messages, "
              << d->points.size() << " points, " << d->options.size() << " options)\n";
    return 0;
  }
  if (verb == "dissector") {
    if (ops.size() != 2) return cli.usage_error("dissector takes one description");
    std::cout << framed::lua_table(*d);
    return 0;
  }
  if (verb == "decode") {
    if (ops.size() < 3) return cli.usage_error("decode needs the bytes, in hex");
    std::string text;
    for (std::size_t i = 2; i < ops.size(); ++i) text += ops[i] + " ";
    const auto bytes = framed::parse_hex(text);
    if (!bytes)
      return cli.usage_error("'" + text + "' is not hex bytes (A5 05 00 ... or A50500...)");
    if (parsed->has("request") && parsed->has("reply")) {
      return cli.usage_error("--request or --reply, not both");
    }
    std::optional<framed::Direction> dir;
    if (parsed->has("request")) dir = framed::Direction::request;
    if (parsed->has("reply")) dir = framed::Direction::reply;
    std::cout << framed::decode_text(*d, *bytes, dir);
    return 0;
  }
  // encode
  if (ops.size() < 3) return cli.usage_error("encode needs a message's name");
  std::vector<std::pair<std::string, double>> fields;
  for (std::size_t i = 3; i < ops.size(); ++i) {
    const auto a = parse_assignment(ops[i]);
    char* end = nullptr;
    const double v = a ? std::strtod(a->value.c_str(), &end) : 0.0;
    if (!a || end == a->value.c_str() || *end != '\0') {
      return cli.usage_error("'" + ops[i] + "' is not FIELD=NUMBER");
    }
    fields.emplace_back(a->point, v);
  }
  std::string error;
  const auto options = options_of(*d, *parsed, error);
  if (!options) return cli.usage_error(error);
  const auto bytes = framed::encode_message(*d, ops[2], fields, *options, error);
  if (!bytes) {
    std::cerr << "drivegate protocol: " << error << "\n";
    return 1;
  }
  std::cout << framed::hex_text(*bytes) << "\n";
  return 0;
}

}  // namespace drivegate::cli
