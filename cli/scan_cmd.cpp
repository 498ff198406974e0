// drivegate scan: which Modbus slaves answer on a serial line, what they say they are, and the
// configuration for them. The probing (which request, how long, how a reply is judged) is the
// modbus adapter's pure Scanner (adapters/modbus/scan.h); this file owns the port, the clock and
// the profiles on disk. The port is opened as the daemon opens a bus (transport/transport.h), so
// a tty is locked the same way and a serial device server works too.
#include <unistd.h>

#include <algorithm>
#include <boost/asio/signal_set.hpp>
#include <boost/asio/steady_timer.hpp>
#include <charconv>
#include <csignal>
#include <filesystem>
#include <functional>
#include <iostream>
#include <set>

#include "app/logging.h"
#include "commands.h"
#include "config/port_address.h"
#include "drivegate/line.h"
#include "scan.h"
#include "scan_progress.h"
#include "scan_report.h"
#include "settings.h"
#include "transport/transport.h"

namespace drivegate::cli {

namespace asio = boost::asio;
namespace md = modbus_device;

namespace {

constexpr Option kScanOptions[] = {
    {"port", 0, "DEVICE",
     "the line: a tty (/dev/ttyUSB0) or a serial device server (tcp://HOST:PORT, "
     "rfc2217://HOST:PORT); required"},
    {"baud", 0, "N", "its baud rate, 300..921600 (default 19200, the Modbus default)"},
    {"parity", 0, "PARITY", "none, even or odd (default even, the Modbus default)"},
    {"data-bits", 0, "N", "7 or 8 (default 8)"},
    {"stop-bits", 0, "N", "1 or 2 (default 1)"},
    {"framing", 0, "FRAMING", "rtu or ascii (default rtu)"},
    {"rs485", 0, nullptr, "turn on the kernel's RS-485 mode on the tty (rs485 = true on a bus)"},
    {"addresses", 'a', "LIST", "the addresses to probe: 1-247 (the default), 17, 1-10,17..."},
    {"timeout-ms", 't', "N",
     "how long a slave may take to start its reply, 10..10000 ms (default 100)"},
    {"profiles", 0, "DIR",
     "also suggest the profiles in DIR (besides the installed and shipped ones)"},
    {"progress", 0, nullptr,
     "show the addresses probed and the time left on stderr, even when it is not a terminal "
     "(default: only in a terminal)"},
    {"no-progress", 0, nullptr, "never show them"},
    kHelpOption,
};

// A number option within [min, max]; nullopt when the text is not one.
std::optional<std::uint32_t> number_in(const std::string& text, std::uint32_t min,
                                       std::uint32_t max) {
  std::uint32_t n = 0;
  const auto [p, ec] = std::from_chars(text.data(), text.data() + text.size(), n);
  if (ec != std::errc{} || p != text.data() + text.size() || n < min || n > max) {
    return std::nullopt;
  }
  return n;
}

// "28 s", "1.6 s": a duration rounded up, tenths below ten seconds.
std::string seconds_text(std::chrono::nanoseconds d) {
  const auto tenths = std::chrono::ceil<std::chrono::duration<long, std::deci>>(d).count();
  if (tenths >= 100) return std::to_string((tenths + 9) / 10) + " s";
  return std::to_string(tenths / 10) + "." + std::to_string(tenths % 10) + " s";
}

// Every profile that names the identification it is for: those found by name (in
// /etc/drivegate/profiles, /usr/share/drivegate/profiles and the shipped ones, in that order of
// precedence, as a device finds them) and the files of `extra` by path. A profile that does not
// load is reported on `err` and left out.
std::vector<KnownProfile> identified_profiles(const std::optional<std::filesystem::path>& extra,
                                              std::ostream& err) {
  std::set<std::string> names;
  for (const auto n : md::shipped_profile_names()) names.emplace(n);
  std::vector<std::string> references;
  const auto toml_files = [](const std::filesystem::path& dir) {
    std::vector<std::filesystem::path> files;
    std::error_code ec;
    for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
      if (e.path().extension() == ".toml") files.push_back(e.path());
    }
    std::sort(files.begin(), files.end());
    return files;
  };
  for (const char* dir : md::kProfileDirs) {
    for (const auto& f : toml_files(dir)) {
      if (md::valid_profile_name(f.stem().string())) names.insert(f.stem().string());
    }
  }
  references.assign(names.begin(), names.end());
  if (extra) {
    for (const auto& f : toml_files(*extra)) references.push_back(f.string());
  }
  std::vector<KnownProfile> out;
  for (const auto& reference : references) {
    std::string error;
    const auto text = md::find_profile(reference, error);
    if (!text) {
      err << "drivegate scan: profile " << reference << ": " << error << "\n";
      continue;
    }
    auto parsed = md::parse_profile(text->text, text->source);
    if (const auto* errors = std::get_if<std::vector<std::string>>(&parsed)) {
      for (const auto& e : *errors) err << "drivegate scan: " << e << "\n";
      continue;
    }
    const auto& profile = std::get<md::Profile>(parsed);
    if (profile.identification) out.push_back({reference, *profile.identification});
  }
  return out;
}

// The scan on the line: the Scanner's requests sent, each after its gap, its replies fed back
// until they end it or its wait runs out. Single-threaded on `io`.
class ScanRun {
 public:
  ScanRun(asio::io_context& io, Transport& transport, md::Scanner& scanner, ScanProgress* progress)
      : transport_(transport),
        scanner_(scanner),
        progress_(progress),
        timer_(io),
        signals_(io, SIGINT, SIGTERM) {}

  // `opened`: called once the port is open, before the first probe.
  void start(std::function<void()> opened) {
    signals_.async_wait([this](const boost::system::error_code& ec, int signal) {
      if (ec) return;
      interrupted_ = signal;
      finish();
    });
    transport_.open([this, opened = std::move(opened)](std::error_code ec) {
      if (finished_) return;  // a signal while a device server was being reached
      if (ec) {
        opened_ = false;
        fail(ec);
        return;
      }
      opened();
      if (progress_ != nullptr) progress_->start(ScanProgress::Clock::now(), counts());
      read();
      step();
    });
  }
  // The port's error, if the scan ended on one; `opened()` says whether it was opening it.
  [[nodiscard]] std::error_code error() const { return error_; }
  [[nodiscard]] bool opened() const { return opened_; }
  // The signal that stopped the scan, or 0.
  [[nodiscard]] int interrupted() const { return interrupted_; }

 private:
  [[nodiscard]] ScanCounts counts() const {
    return {scanner_.probed(), scanner_.total(), scanner_.found().size(), scanner_.time_left()};
  }

  void read() {
    transport_.read([this](std::error_code ec, ByteView bytes) {
      if (finished_) return;
      if (ec) {
        fail(ec);
        return;
      }
      if (scanner_.on_receive(bytes)) step();
      if (!finished_) read();
    });
  }

  // The next request: its gap, then its frame, then its wait. Every step starts a generation of
  // its own, so that a timer of the one before that fires late does nothing.
  void step() {
    const unsigned generation = ++generation_;
    timer_.cancel();
    if (progress_ != nullptr) progress_->tick(ScanProgress::Clock::now(), counts());
    auto request = scanner_.next();
    if (!request) {
      finish();
      return;
    }
    request_ = std::move(*request);
    if (request_.frame.empty()) {  // nothing to send: only the line listened to
      wait(generation);
      return;
    }
    timer_.expires_after(request_.gap);
    timer_.async_wait([this, generation](const boost::system::error_code& ec) {
      if (ec || generation != generation_ || finished_) return;
      transport_.write(request_.frame, [this, generation](std::error_code written) {
        if (generation != generation_ || finished_) return;
        if (written) {
          fail(written);
          return;
        }
        wait(generation);
      });
    });
  }

  // The request's wait: its reply ends it sooner (read()), else the Scanner hears it ran out.
  void wait(unsigned generation) {
    timer_.expires_after(request_.wait);
    timer_.async_wait([this, generation](const boost::system::error_code& expired) {
      if (expired || generation != generation_ || finished_) return;
      scanner_.on_timeout();
      step();
    });
  }

  void fail(std::error_code ec) {
    error_ = ec;
    finish();
  }

  void finish() {
    if (finished_) return;
    finished_ = true;
    if (progress_ != nullptr && opened_) progress_->finish(ScanProgress::Clock::now(), counts());
    timer_.cancel();
    signals_.cancel();
    transport_.close();
  }

  Transport& transport_;
  md::Scanner& scanner_;
  ScanProgress* progress_;
  asio::steady_timer timer_;
  asio::signal_set signals_;
  md::ScanRequest request_;
  unsigned generation_ = 0;
  bool finished_ = false;
  bool opened_ = true;
  int interrupted_ = 0;
  std::error_code error_;
};

}  // namespace

int scan(std::span<const std::string> args) {
  const CommandLine cli(
      "drivegate scan", kScanOptions, {"--port DEVICE [--baud N] [--parity P] [OPTION]..."},
      "Probes each address with a read of holding register 0 (any reply, registers or an\n"
      "exception, is a slave), asks each slave found for its identification (FC 0x2B / 0x0E,\n"
      "basic), and prints a line per slave, a summary and the configuration for them, with the\n"
      "profile whose [profile] identification matches (docs/profiles.md). A silent address\n"
      "costs one timeout: 247 addresses at 100 ms and 19200 baud take at most 29 s. Stop the\n"
      "daemon first if it owns the port. Exit status 0 when the scan ran, whether or not a\n"
      "slave answered.");
  int exit_status = 0;
  const auto parsed = parse_command(cli, args, exit_status);
  if (!parsed) return exit_status;
  if (!parsed->operands.empty()) {
    return cli.usage_error("unexpected argument '" + parsed->operands.front() + "'");
  }
  BusConfig line;
  line.name = "scan";
  line.port = parsed->value("port").value_or("");
  if (line.port.empty()) return cli.usage_error("--port is required");
  std::string port_error;
  if (!parse_port_address(line.port, port_error)) {
    return cli.usage_error("--port: " + port_error);
  }
  line.baud = 19200;  // Serial Line 2.5.1: 19200 baud, even parity are every device's default
  line.parity = Parity::even;
  if (const auto v = parsed->value("baud")) {
    const auto n = number_in(*v, 300, 921600);
    if (!n) return cli.usage_error("--baud must be 300..921600, not '" + *v + "'");
    line.baud = *n;
  }
  if (const auto v = parsed->value("parity")) {
    const auto p = parse_parity(*v);
    if (!p) return cli.usage_error("--parity must be none, even or odd, not '" + *v + "'");
    line.parity = *p;
  }
  if (const auto v = parsed->value("data-bits")) {
    const auto n = number_in(*v, 7, 8);
    if (!n) return cli.usage_error("--data-bits must be 7 or 8, not '" + *v + "'");
    line.data_bits = static_cast<std::uint8_t>(*n);
  }
  if (const auto v = parsed->value("stop-bits")) {
    const auto n = number_in(*v, 1, 2);
    if (!n) return cli.usage_error("--stop-bits must be 1 or 2, not '" + *v + "'");
    line.stop_bits = static_cast<std::uint8_t>(*n);
  }
  line.rs485 = parsed->has("rs485");
  md::ScanSettings settings;
  if (const auto v = parsed->value("framing")) {
    if (*v == "ascii") {
      settings.framing = md::Framing::ascii;
    } else if (*v != "rtu") {
      return cli.usage_error("--framing must be rtu or ascii, not '" + *v + "'");
    }
  }
  const std::string addresses = parsed->value("addresses").value_or("1-247");
  std::string address_error;
  const auto list = md::parse_addresses(addresses, address_error);
  if (!list) return cli.usage_error("--addresses: " + address_error);
  settings.addresses = *list;
  if (const auto v = parsed->value("timeout-ms")) {
    const auto n = number_in(*v, 10, 10000);
    if (!n) return cli.usage_error("--timeout-ms must be 10..10000, not '" + *v + "'");
    settings.timeout = std::chrono::milliseconds(*n);
  }
  std::optional<std::filesystem::path> profile_dir;
  if (const auto v = parsed->value("profiles")) {
    std::error_code ec;
    if (!std::filesystem::is_directory(*v, ec)) {
      std::cerr << "drivegate scan: --profiles " << *v << " is not a directory\n";
      return 1;
    }
    profile_dir = *v;
  }
  const bool tty = ::isatty(STDERR_FILENO) == 1;
  const auto progress_flag = parsed->last_of({"progress", "no-progress"});
  const bool show_progress = progress_flag ? *progress_flag == "progress" : tty;
  settings.char_time = character_time(line.baud, line.parity, line.data_bits, line.stop_bits);
  md::Scanner scanner(settings);

  asio::io_context io;
  auto transport = make_transport(io, line, make_logger("drivegate", spdlog::level::warn));
  ScanProgress progress(std::cerr, tty);
  ScanRun run(io, *transport, scanner, show_progress ? &progress : nullptr);
  run.start([&] {
    // The bound before the first probe, so that a long scan is no surprise.
    const auto n = scanner.total();
    std::cerr << "drivegate scan: " << n << (n == 1 ? " address" : " addresses") << " on "
              << transport->describe() << ", "
              << md::kFramingNames[static_cast<std::size_t>(settings.framing)] << ", "
              << settings.timeout.count() << " ms each: at most "
              << seconds_text(scanner.time_left()) << " if none answers, "
              << seconds_text(scanner.answer_time()) << " more for each that does\n";
    if (const std::string caveat = transport->caveat(); !caveat.empty()) {
      std::cerr << "drivegate scan: warning: " << caveat << "\n";
    }
  });
  io.run();
  if (run.error() && !run.opened()) {
    std::cerr << "drivegate scan: cannot open " << line.port << ": "
              << transport->explain(run.error()) << "\n";
    return 1;
  }
  const auto profiles = scanner.found().empty() ? std::vector<KnownProfile>()
                                                : identified_profiles(profile_dir, std::cerr);
  ScanReport report;
  report.line = line;
  report.framing = settings.framing;
  report.addresses = addresses;
  report.scanner = &scanner;
  report.profiles = profiles;
  report.interrupted = run.interrupted() != 0 || run.error();
  std::cout << scan_report(report) << std::flush;
  if (run.error()) {
    std::cerr << "drivegate scan: " << line.port << ": " << transport->explain(run.error())
              << " (the scan stopped there)\n";
    return 1;
  }
  // Stopped by a signal: what was found so far is out, and the status says it was cut short.
  return run.interrupted() != 0 ? 128 + run.interrupted() : 0;
}

}  // namespace drivegate::cli
