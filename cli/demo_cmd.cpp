// drivegate demo: a simulator for every installed adapter, the real daemon on them, and each
// drive started at a typical speed, so a newcomer sees live values within seconds. Everything
// adapter-specific comes from the descriptors (AdapterDescriptor::demo): an adapter added later
// appears here without a change to this file.
#include <modbus/modbus.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <boost/asio/io_context.hpp>
#include <boost/asio/signal_set.hpp>
#include <csignal>
#include <fstream>
#include <iostream>
#include <sstream>
#include <thread>

#include "commands.h"
#include "config/config_loader.h"
#include "plugin/adapter_options.h"
#include "sim_host.h"

extern char** environ;

namespace drivegate::cli {

namespace asio = boost::asio;

namespace {

constexpr Option kDemoOptions[] = {
    {"listen", 'l', "HOST:PORT", "where the daemon serves Modbus TCP (default 127.0.0.1:1502)"},
    {"no-start", 0, nullptr, "leave the drives stopped"},
    kPluginDirOption,
    kHelpOption,
};

// The adapter's demo options (AdapterDescriptor::demo) over its defaults, for the simulator and
// the device alike; `error` names a bad one (a plugin bug: its own demo does not validate).
std::optional<Options> demo_options(const AdapterDescriptor& a, std::string& error) {
  Options options = default_options(a);
  for (std::size_t i = 0; i < a.demo.option_count; ++i) {
    const OptionSetting& o = a.demo.options[i];
    if (!set_option_text(a, options, o.name, o.value, error)) return std::nullopt;
  }
  return options;
}

// The [device.options] table of the demo device: its demo options, as TOML.
std::string options_table(const AdapterDescriptor& a, const Options& options) {
  std::string out;
  for (std::size_t i = 0; i < a.demo.option_count; ++i) {
    const char* name = a.demo.options[i].name;
    out += std::string(name) + " = " + toml_literal(options.value(name)) + "\n";
  }
  return out.empty() ? out : "[device.options]\n" + out;
}

std::filesystem::path self_path() {
  std::error_code ec;
  auto self = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::filesystem::path("drivegate") : self;
}

// The daemon beside this program (the build tree's bin/), else the installed one.
std::filesystem::path daemon_binary() {
  auto beside = self_path().parent_path() / "drivegated";
  std::error_code ec;
  if (std::filesystem::exists(beside, ec)) return beside;
  return "/usr/sbin/drivegated";
}

// Waits for the unit to come online, then writes setpoint and run_forward in one request, as
// a PLC would.
bool start_drive(const std::string& host, int port, int unit, int rpm) {
  modbus_t* ctx = modbus_new_tcp(host.c_str(), port);
  if (ctx == nullptr) return false;
  modbus_set_slave(ctx, unit);
  modbus_set_response_timeout(ctx, 5, 0);
  bool ok = false;
  if (modbus_connect(ctx) == 0) {
    std::uint16_t status = 0;
    for (int i = 0; i < 100; ++i) {
      if (modbus_read_input_registers(ctx, 0, 1, &status) == 1 && (status & 1u) != 0) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    const std::uint16_t regs[2] = {1 /*run_forward*/, static_cast<std::uint16_t>(rpm)};
    ok = (status & 1u) != 0 && modbus_write_registers(ctx, 0, 2, regs) == 2;
    modbus_close(ctx);
  }
  modbus_free(ctx);
  return ok;
}

bool port_answers(const std::string& host, int port) {
  modbus_t* ctx = modbus_new_tcp(host.c_str(), port);
  if (ctx == nullptr) return false;
  const bool ok = modbus_connect(ctx) == 0;
  if (ok) modbus_close(ctx);
  modbus_free(ctx);
  return ok;
}

}  // namespace

int demo(std::span<const std::string> args) {
  const CommandLine cli(
      "drivegate demo", kDemoOptions, {"[-l HOST:PORT] [--no-start] [-p DIR]"},
      "Starts a simulated drive for every installed adapter, the daemon on them (Modbus TCP on\n"
      "127.0.0.1:1502 by default, the status page on the Modbus port + 7000, 8502 by default),\n"
      "and each drive at a typical speed. Ctrl-C stops everything.");
  int exit_status = 0;
  const auto parsed = parse_command(cli, args, exit_status);
  if (!parsed) return exit_status;
  if (!parsed->operands.empty()) {
    return cli.usage_error("unexpected argument '" + parsed->operands.front() + "'");
  }
  const std::filesystem::path plugin_dir = parsed->value("plugin-dir").value_or("");
  ListenAddress listen{"127.0.0.1", 1502};
  if (const auto v = parsed->value("listen")) {
    auto at = parse_listen(*v);
    if (!at)
      return cli.usage_error("--listen needs HOST:PORT (e.g. 127.0.0.1:1502), not '" + *v + "'");
    listen = std::move(*at);
  }
  const bool start = !parsed->has("no-start");
  const PluginRegistry plugins = load_plugins(plugin_dir);
  if (plugins.all().empty()) {
    std::cerr << "drivegate demo: no adapters installed\n";
    return 1;
  }
  char tmpl[] = "/tmp/drivegate-demo-XXXXXX";
  if (::mkdtemp(tmpl) == nullptr) {
    std::cerr << "drivegate demo: cannot create a temporary directory\n";
    return 1;
  }
  const std::filesystem::path dir = tmpl;

  asio::io_context io;
  std::vector<std::unique_ptr<SimHost>> sims;
  std::ostringstream config;
  // Simulated drives: the demo's client may do everything a commissioning engineer would try.
  // On loopback only loopback may connect; elsewhere the daemon warns that anyone may write.
  config << "# generated by drivegate demo\n[[listener]]\naddress = \"" << listen.host << ":"
         << listen.port << "\"\naccess = \"maintain\"\n"
         << (listen.host == "127.0.0.1" ? "allow = [\"127.0.0.1\"]\n" : "");
  // The status page, metrics and captures, beside it (loopback only, like the example).
  const int http_port = (listen.port + 7000) % 65536;
  config << "\n[http]\nlisten = \"127.0.0.1:" << http_port << "\"\ncapture = true\n";
  struct Unit {
    int unit;
    std::string id;
    int rpm;
  };
  std::vector<Unit> units;
  for (const AdapterDescriptor* a : plugins.all()) {
    std::string error;
    auto options = demo_options(*a, error);
    if (!options) {
      std::cerr << "drivegate demo: adapter '" << a->id << "': demo option " << error << "\n";
      return 1;
    }
    // A described protocol's device runs on its description's line (AdapterDescriptor::specialise).
    const AdapterDescriptor* device = specialised(*a, *options, error);
    if (device == nullptr) {
      std::cerr << "drivegate demo: adapter '" << a->id << "': " << error << "\n";
      return 1;
    }
    SimHostOptions so;
    so.addresses = {device->default_address};
    so.options = *options;  // the simulator takes the same options the device gets
    so.echo = device->line.echo;
    so.link = dir / a->id;
    auto host = std::make_unique<SimHost>(io, *device, so);
    if (const auto why = host->open(); !why.empty()) {
      std::cerr << "drivegate demo: " << a->id << ": " << why << "\n";
      return 1;
    }
    host->start();
    const int unit = static_cast<int>(units.size()) + 1;
    config << "\n[[bus]]\nname = \"" << a->id << "\"\nport = \"" << host->path() << "\"\n"
           << "\n[[device]]\nname = \"" << a->id << "\"\nbus = \"" << a->id << "\"\nadapter = \""
           << a->id << "\"\nunit_id = " << unit << "\n";
    config << options_table(*a, *options);
    units.push_back({unit, a->id, a->demo.running_rpm});
    sims.push_back(std::move(host));
  }
  const auto config_path = dir / "demo.toml";
  std::ofstream(config_path) << config.str();

  const auto daemon = daemon_binary();
  const std::string listen_text = listen.host + ":" + std::to_string(listen.port);
  std::vector<std::string> argv_s = {daemon.string(), "--config", config_path.string(), "--listen",
                                     listen_text};
  if (!plugin_dir.empty()) {
    argv_s.emplace_back("--plugin-dir");
    argv_s.push_back(plugin_dir.string());
  }
  std::vector<char*> argv;
  argv.reserve(argv_s.size() + 1);
  for (auto& s : argv_s) argv.push_back(s.data());
  argv.push_back(nullptr);
  pid_t child = -1;
  if (posix_spawn(&child, argv[0], nullptr, nullptr, argv.data(), environ) != 0) {
    std::cerr << "drivegate demo: cannot start " << daemon << "\n";
    return 1;
  }

  int exit_code = 0;
  // Ctrl-C: the daemon is told first and the simulators keep answering until it has stopped
  // every drive and exited, as a real shutdown would go; only then does the demo end.
  bool stopping = false;
  asio::signal_set signals(io, SIGINT, SIGTERM, SIGCHLD);
  std::function<void()> wait_signal = [&] {
    signals.async_wait([&](const boost::system::error_code& ec, int signo) {
      if (ec) return;
      if (signo != SIGCHLD) {
        if (!stopping && child > 0) ::kill(child, signo);
        stopping = true;
        wait_signal();
        return;
      }
      int status = 0;
      if (::waitpid(child, &status, WNOHANG) != child) {
        wait_signal();
        return;
      }
      child = -1;
      if (!stopping) {
        std::cerr << "drivegate demo: the daemon exited\n";
        exit_code = 1;
      }
      io.stop();
    });
  };
  wait_signal();

  // The simulators live on this thread's io_context; talking Modbus to the daemon (which waits
  // on them) happens on another, so neither ever waits for the other.
  std::atomic<bool> quit{false};
  std::atomic<bool> gave_up{false};
  std::thread client([&] {
    int tries = 0;
    while (!quit && !port_answers(listen.host, listen.port)) {
      if (++tries > 100) {
        std::cerr << "drivegate demo: the daemon does not answer on " << listen_text << "\n";
        gave_up = true;
        ::kill(::getpid(), SIGTERM);
        return;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    std::ostringstream out;
    out << "\ndrivegate demo: Modbus TCP on " << listen_text << "\n\n"
        << "  unit  adapter          state\n";
    for (const auto& u : units) {
      if (quit) return;
      const bool ok = start && start_drive(listen.host, listen.port, u.unit, u.rpm);
      std::string name = u.id;
      name.resize(std::max<std::size_t>(name.size(), 16), ' ');
      out << "  " << u.unit << "     " << name << " "
          << (ok ? "running at " + std::to_string(u.rpm) + " rpm"
                 : std::string(start ? "not started (see the log above)" : "stopped"))
          << "\n";
    }
    const std::string host = listen.host == "0.0.0.0" ? "127.0.0.1" : listen.host;
    out << "\nRead unit 1's common input block: status, faults, speed, data age and counters\n"
        << "(input registers 0..30; mbpoll's -r is the 1-based reference, and -t 3 shows 32-bit\n"
        << "values as two 16-bit words, high word first):\n"
        << "  mbpoll -m tcp -p " << listen.port << " -a 1 -t 3 -r 1 -c 31 -1 " << host << "\n"
        << "One 32-bit value as a number (data_age_ms, input register 7; -B: high word first,\n"
        << "the listener's word order):\n"
        << "  mbpoll -m tcp -p " << listen.port << " -a 1 -t 3:int -B -r 8 -c 1 -1 " << host << "\n"
        << "Stop it (holding register 0 is the command; 0 = stop, 1 = run_forward):\n"
        << "  mbpoll -m tcp -p " << listen.port << " -a 1 -t 4 -r 1 " << host << " 0\n"
        << "The status page (live, read-only) and Prometheus metrics:\n"
        << "  http://127.0.0.1:" << http_port << "/   and   http://127.0.0.1:" << http_port
        << "/metrics\n"
        << "A capture of a bus for Wireshark (dissectors in tools/wireshark/):\n"
        << "  " << self_path().string() << " capture --http 127.0.0.1:" << http_port << " --bus "
        << (units.empty() ? std::string("BUS") : units.front().id) << " --seconds 5 -w bus.pcap\n"
        << "The register map of every unit:\n"
        << "  " << self_path().string() << " regmap --config " << config_path.string()
        << " --format md\n"
        << "\nCtrl-C stops the demo.\n";
    std::cout << out.str() << std::flush;
  });
  io.run();
  quit = true;
  client.join();
  if (gave_up) exit_code = 1;

  if (child > 0) {  // the client thread gave up on the daemon
    ::kill(child, SIGTERM);
    int status = 0;
    ::waitpid(child, &status, 0);
  }
  for (auto& s : sims) s->stop();
  std::error_code ec;
  std::filesystem::remove_all(dir, ec);
  return exit_code;
}

}  // namespace drivegate::cli
