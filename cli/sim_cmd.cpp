// drivegate sim: one adapter's simulated device(s) on a new pseudo-terminal or a real port.
#include <unistd.h>

#include <boost/asio/posix/stream_descriptor.hpp>
#include <boost/asio/read_until.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/asio/streambuf.hpp>
#include <csignal>
#include <iostream>

#include "commands.h"
#include "plugin/adapter_options.h"
#include "sim_host.h"

namespace drivegate::cli {

namespace asio = boost::asio;

namespace {

constexpr Option kSimOptions[] = {
    {"address", 'a', "N",
     "the simulated device's bus address; repeat for several devices on one line (default: the "
     "adapter's default address)"},
    {"set", 0, "OPTION=VALUE", "an adapter option, as in [device.options]"},
    {"cmd", 0, "LINE", "an operator command to run at start (repeatable)"},
    {"link", 0, "PATH", "also make PATH a symbolic link to the pseudo-terminal"},
    {"port", 0, "DEVICE", "a real serial port instead of a pseudo-terminal"},
    {"baud", 0, "N", "the real port's baud rate (default: the adapter's)"},
    {"parity", 0, "PARITY", "the real port's parity: none, even or odd (default: the adapter's)"},
    {"echo", 0, nullptr, "echo the bytes received, as a one-wire line does"},
    {"no-echo", 0, nullptr, "do not echo them (default: what the adapter's line does)"},
    {"turnaround-ms", 0, "N", "delay before each reply, in milliseconds"},
    {"turnaround-us", 0, "N", "delay before each reply, in microseconds"},
    {"wire-timing", 0, nullptr,
     "each byte takes the character time of the line (--baud/--parity, else the adapter's "
     "defaults) and replies start one turnaround after the request's last character"},
    {"wire-log", 0, "FILE",
     "with --wire-timing: record when each chunk arrived and each reply went out (nanoseconds)"},
    kPluginDirOption,
    kHelpOption,
};

// A number option's value, the way the C library reads it (0x.. for hexadecimal where `base` is
// 0); nullopt unless the whole text is one.
std::optional<unsigned long> number(const std::string& text, int base) {
  try {
    std::size_t used = 0;
    const unsigned long n = std::stoul(text, &used, base);
    if (used != text.size()) return std::nullopt;
    return n;
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

// Reads stdin lines and answers them on stdout; stdin at end (or not pollable) is ignored.
class ControlConsole {
 public:
  ControlConsole(asio::io_context& io, SimHost& host) : in_(io), host_(host) {
    boost::system::error_code ec;
    in_.assign(::dup(STDIN_FILENO), ec);
    if (!ec) read();
  }

 private:
  void read() {
    asio::async_read_until(in_, buffer_, '\n',
                           [this](const boost::system::error_code& ec, std::size_t) {
                             if (ec) return;
                             std::istream is(&buffer_);
                             std::string line;
                             std::getline(is, line);
                             if (!line.empty() && line.back() == '\r') line.pop_back();
                             if (!line.empty()) std::cout << host_.control(line) << std::endl;
                             read();
                           });
  }
  asio::posix::stream_descriptor in_;
  asio::streambuf buffer_;
  SimHost& host_;
};

}  // namespace

int sim(std::span<const std::string> args) {
  const CommandLine cli(
      "drivegate sim", kSimOptions,
      {"ADAPTER [-a N]... [--set OPTION=VALUE]... [OPTION]...",
       "ADAPTER --port DEVICE [--baud N] [--parity P] [OPTION]..."},
      "Prints the line's path on the first line of stdout, then reads operator commands from\n"
      "stdin (`help` lists them; `@ADDR CMD` sends to one address when there are several).");
  int exit_status = 0;
  const auto parsed = parse_command(cli, args, exit_status);
  if (!parsed) return exit_status;
  if (parsed->operands.empty()) return cli.usage_error("which adapter?");
  if (parsed->operands.size() > 1) return cli.usage_error("one adapter only");
  const std::string& adapter_id = parsed->operands.front();
  const std::filesystem::path plugin_dir = parsed->value("plugin-dir").value_or("");
  SimHostOptions options;
  // A number option: its value, or the usage error naming it.
  std::optional<std::string> bad;
  const auto numeric = [&](std::string_view name, const std::string& text,
                           int base) -> unsigned long {
    const auto n = number(text, base);
    if (!n && !bad) bad = "--" + std::string(name) + ": '" + text + "' is not a number";
    return n.value_or(0);
  };
  for (const auto& a : parsed->values("address")) {
    options.addresses.push_back(static_cast<std::uint32_t>(numeric("address", a, 0)));
  }
  std::vector<std::pair<std::string, std::string>> sets;
  for (const auto& v : parsed->values("set")) {
    const auto eq = v.find('=');
    if (eq == std::string::npos)
      return cli.usage_error("--set needs OPTION=VALUE, not '" + v + "'");
    sets.emplace_back(v.substr(0, eq), v.substr(eq + 1));
  }
  const std::vector<std::string> commands = parsed->values("cmd");
  if (const auto v = parsed->value("link")) options.link = *v;
  BusConfig port;
  if (const auto v = parsed->value("port")) port.port = *v;
  if (const auto v = parsed->value("baud"))
    port.baud = static_cast<std::uint32_t>(numeric("baud", *v, 10));
  std::optional<Parity> parity;
  if (const auto v = parsed->value("parity")) {
    parity = parse_parity(*v);
    if (!parity) return cli.usage_error("--parity must be none, even or odd, not '" + *v + "'");
  }
  std::optional<bool> echo;
  if (const auto last = parsed->last_of({"echo", "no-echo"})) echo = *last == "echo";
  if (const auto last = parsed->last_of({"turnaround-ms", "turnaround-us"})) {
    const std::string name(*last);
    const unsigned long n = numeric(name, *parsed->value(name), 10);
    if (name == "turnaround-ms") {
      options.turnaround = Millis(n);
    } else {
      options.turnaround = std::chrono::microseconds(n);
    }
  }
  if (const auto v = parsed->value("wire-log")) options.wire_log = *v;
  const bool wire_timing = parsed->has("wire-timing");
  if (bad) return cli.usage_error(*bad);
  const PluginRegistry plugins = load_plugins(plugin_dir);
  const AdapterDescriptor* adapter = plugins.find(adapter_id);
  if (adapter == nullptr) {
    std::cerr << "drivegate sim: no adapter '" << adapter_id << "' (installed: " << plugins.ids()
              << ")\n";
    return 1;
  }
  if (adapter->specialise != nullptr) {
    // A described protocol (the framed adapter): its own options, line and addresses come from
    // the description the adapter's own options (--set protocol=NAME) name.
    Options base = default_options(*adapter);
    for (const auto& [key, text] : sets) {
      std::string ignored;  // the description's own options: judged once it is known
      set_option_text(*adapter, base, key, text, ignored);
    }
    std::string error;
    adapter = specialised(*adapter, base, error);
    if (adapter == nullptr) {
      std::cerr << "drivegate sim: " << adapter_id << ": " << error << "\n";
      return 1;
    }
  }
  options.options = default_options(*adapter);
  for (const auto& [key, text] : sets) {
    std::string error;
    if (!set_option_text(*adapter, options.options, key, text, error)) {
      return cli.usage_error(error);
    }
  }
  options.echo = echo.value_or(adapter->line.echo);
  if (port.baud == 0) port.baud = adapter->line.baud;
  port.parity = parity.value_or(adapter->line.parity);
  port.data_bits = adapter->line.data_bits;
  port.stop_bits = adapter->line.stop_bits;
  if (!port.port.empty()) options.port = port;
  if (wire_timing) {
    options.char_time = character_time(port.baud, port.parity, port.data_bits, port.stop_bits);
  } else if (options.wire_log) {
    return cli.usage_error("--wire-log needs --wire-timing");
  }

  asio::io_context io;
  SimHost host(io, *adapter, options);
  if (const std::string why = host.open(); !why.empty()) {
    std::cerr << "drivegate sim: " << why << "\n";
    return 1;
  }
  std::cout << host.path() << std::endl;
  std::cerr << "drivegate sim: " << adapter_id << " on " << host.path()
            << (options.echo ? " (one-wire echo)" : "")
            << (wire_timing ? ", wire timing " + std::to_string(options.char_time.count()) +
                                  " ns per character"
                            : std::string())
            << "; type 'help' for commands\n";
  for (const auto& c : commands) std::cout << host.control(c) << std::endl;
  host.start();
  ControlConsole console(io, host);
  asio::signal_set signals(io, SIGINT, SIGTERM);
  signals.async_wait([&](const boost::system::error_code&, int) {
    host.stop();
    io.stop();
  });
  io.run();
  return 0;
}

}  // namespace drivegate::cli
