// drivegate sim: one adapter's simulated device(s) on a new pseudo-terminal or a real port.
#include <unistd.h>

#include <boost/asio/posix/stream_descriptor.hpp>
#include <boost/asio/read_until.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/asio/streambuf.hpp>
#include <csignal>
#include <iostream>

#include "commands.h"
#include "config/adapter_options.h"
#include "sim_host.h"

namespace drivegate::cli {

namespace asio = boost::asio;

namespace {

constexpr const char* kUsage =
    "usage: drivegate sim ADAPTER [--address N]... [--set OPTION=VALUE]... [--cmd LINE]...\n"
    "                 [--link PATH] [--port DEVICE --baud N --parity none|even|odd]\n"
    "                 [--echo | --no-echo] [--turnaround-ms N | --turnaround-us N]\n"
    "                 [--wire-timing [--wire-log FILE]] [--plugin-dir DIR]\n"
    "\n"
    "--wire-timing: each byte takes the character time of the line (--baud/--parity, else the\n"
    "adapter's defaults) and replies start one turnaround after the request's last character.\n"
    "--wire-log FILE records when each chunk arrived and each reply went out (nanoseconds).\n"
    "Prints the line's path on the first line of stdout, then reads operator commands from\n"
    "stdin (`help` lists them; `@ADDR CMD` sends to one address when there are several).\n";

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

int sim(std::span<const std::string_view> args) {
  ArgReader r("sim", args);
  std::string adapter_id;
  std::filesystem::path plugin_dir;
  SimHostOptions options;
  std::vector<std::pair<std::string, std::string>> sets;
  std::vector<std::string> commands;
  std::optional<bool> echo;
  bool wire_timing = false;
  BusConfig port;
  std::optional<Parity> parity;
  while (!r.done()) {
    const auto arg = r.next();
    if (arg == "--help") {
      std::cout << kUsage;
      return 0;
    }
    if (arg == "--wire-timing") {
      wire_timing = true;
      continue;
    }
    if (arg == "--echo" || arg == "--no-echo") {
      echo = arg == "--echo";
      continue;
    }
    if (!arg.starts_with("--")) {
      if (!adapter_id.empty()) return r.usage("one adapter only", kUsage);
      adapter_id = arg;
      continue;
    }
    auto v = r.value(arg);
    if (!v) return 2;
    try {
      if (arg == "--address") {
        options.addresses.push_back(static_cast<std::uint32_t>(std::stoul(*v, nullptr, 0)));
      } else if (arg == "--set") {
        const auto eq = v->find('=');
        if (eq == std::string::npos) return r.usage("--set needs OPTION=VALUE", kUsage);
        sets.emplace_back(v->substr(0, eq), v->substr(eq + 1));
      } else if (arg == "--cmd") {
        commands.push_back(*v);
      } else if (arg == "--link") {
        options.link = *v;
      } else if (arg == "--port") {
        port.port = *v;
      } else if (arg == "--baud") {
        port.baud = static_cast<std::uint32_t>(std::stoul(*v));
      } else if (arg == "--parity") {
        if (*v != "none" && *v != "even" && *v != "odd") {
          return r.usage("--parity must be none, even or odd", kUsage);
        }
        parity = *v == "none" ? Parity::none : *v == "even" ? Parity::even : Parity::odd;
      } else if (arg == "--turnaround-ms") {
        options.turnaround = Millis(std::stoul(*v));
      } else if (arg == "--turnaround-us") {
        options.turnaround = std::chrono::microseconds(std::stoul(*v));
      } else if (arg == "--wire-log") {
        options.wire_log = *v;
      } else if (arg == "--plugin-dir") {
        plugin_dir = *v;
      } else {
        return r.usage("unknown argument '" + std::string(arg) + "'", kUsage);
      }
    } catch (const std::exception&) {
      return r.usage(std::string(arg) + ": '" + *v + "' is not a number", kUsage);
    }
  }
  if (adapter_id.empty()) return r.usage("which adapter?", kUsage);
  const PluginRegistry plugins = load_plugins(plugin_dir);
  const AdapterDescriptor* adapter = plugins.find(adapter_id);
  if (adapter == nullptr) {
    std::cerr << "drivegate sim: no adapter '" << adapter_id << "' (installed: " << plugins.ids()
              << ")\n";
    return 1;
  }
  options.options = default_options(*adapter);
  for (const auto& [key, text] : sets) {
    std::string error;
    if (!set_option_text(*adapter, options.options, key, text, error)) {
      return r.usage(error, kUsage);
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
    return r.usage("--wire-log needs --wire-timing", kUsage);
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
