#include "daemon_http.h"

#include <boost/asio/ip/address.hpp>
#include <iostream>

#include "config/config_loader.h"
#include "net/allow_list.h"

namespace drivegate::cli {

namespace {

bool every_address(const std::string& host) {
  return host.empty() || host == "*" || host == "0.0.0.0" || host == "::";
}

}  // namespace

std::optional<DaemonHttp> daemon_http(const CommandLine& cli, std::string_view program,
                                      const ParsedArgs& parsed, int& exit_status) {
  DaemonHttp out;
  if (const auto v = parsed.value("http")) {
    auto at = parse_listen(*v);
    if (!at) {
      exit_status = cli.usage_error("--http needs HOST:PORT, not '" + *v + "'");
      return std::nullopt;
    }
    out.host = at->host;
    out.port = at->port;
    out.found = "--http";
    return out;
  }
  exit_status = 1;
  const std::string file = parsed.value("config").value_or(kDefaultConfig);
  auto result = load_http_config(file);
  if (!result.config) {
    for (const auto& e : result.errors) std::cerr << e << "\n";
    std::cerr << program << ": cannot tell where the daemon's HTTP side is from " << file
              << ": give its configuration (--config FILE) or the address (--http HOST:PORT)\n";
    return std::nullopt;
  }
  const HttpConfig& http = result.config->http;
  if (!http.enabled) {
    std::cerr << program << ": " << file
              << " has no [http]: the daemon serves no HTTP side to ask (add [http] with "
                 "listen = \"127.0.0.1:8502\" and restart it: docs/http.md), or give the "
                 "address with --http HOST:PORT\n";
    return std::nullopt;
  }
  const bool v6 = http.listen.host.find(':') != std::string::npos;
  // Listening on every address: ask on this machine's loopback, of the same family.
  out.host = every_address(http.listen.host) ? (v6 ? "::1" : "127.0.0.1") : http.listen.host;
  out.port = http.listen.port;
  out.found = "the [http] listen of " + file;
  out.config = file;
  out.capture = http.capture;
  boost::system::error_code ec;
  const auto ours = boost::asio::ip::make_address(out.host, ec);
  out.open_to_us = ec || !ours.is_loopback() || net::allowed(http.allow, ours);
  exit_status = 0;
  return out;
}

std::string unreachable(const DaemonHttp& at, const std::string& why) {
  std::string out = at.host + ":" + std::to_string(at.port) + " (" + at.found + "): " + why;
  while (!out.empty() && (out.back() == '\n' || out.back() == '\r')) out.pop_back();
  const bool refused = why.find("refused") != std::string::npos;
  const bool silent = why.find("not an HTTP response") != std::string::npos;
  if (refused && !at.config.empty()) {
    out += "; is drivegated running with " + at.config +
           "? (systemctl status drivegate; an [http] added or changed applies at a restart)";
  } else if (refused) {
    out += "; is drivegated running, its [http] listening there?";
  } else if (silent && !at.open_to_us) {
    out += "; " + at.config + "'s [http] allow does not let this machine's loopback in";
  } else if (silent) {
    out += "; closed without an answer: is this address in the daemon's [http] allow?";
  }
  return out;
}

}  // namespace drivegate::cli
