// Where the running daemon's HTTP side is, for the commands that ask it (events, capture): the
// [http] listen of its configuration (--config FILE, by default the packaged service's), or
// --http HOST:PORT as given. And what to say when it cannot be reached: where the command looked,
// found from what, and what most likely stands in the way.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "base/command_line.h"

namespace drivegate::cli {

// The packaged service's configuration (systemd/drivegate.service).
inline constexpr const char* kDefaultConfig = "/etc/drivegate/drivegate.toml";

inline constexpr Option kDaemonConfigOption{
    "config", 'c', "FILE",
    "the daemon's configuration, whose [http] listen says where to ask it (default "
    "/etc/drivegate/drivegate.toml)"};
inline constexpr Option kHttpOption{"http", 0, "HOST:PORT",
                                    "ask the daemon's HTTP side there instead of where FILE says"};

struct DaemonHttp {
  std::string host;  // an [http] listen on every address is asked on loopback
  std::uint16_t port = 0;
  std::string found;       // how: "--http", "the [http] listen of FILE"
  std::string config;      // FILE, when read from it
  bool capture = true;     // FILE's [http] capture (with --http: not known, so not refused here)
  bool open_to_us = true;  // FILE's [http] allow lets loopback in (with --http: not known)
};

// From `parsed` (a table with kDaemonConfigOption and kHttpOption): nullopt after saying why on
// stderr as `program` ("drivegate events"), with the status to exit with in `exit_status` (2: a
// usage error, 1: a file that does not say where the daemon is).
std::optional<DaemonHttp> daemon_http(const CommandLine& cli, std::string_view program,
                                      const ParsedArgs& parsed, int& exit_status);

// "127.0.0.1:8502 (the [http] listen of FILE): WHY", and a hint when WHY suggests one (refused:
// the daemon is not running with that [http]; closed without an answer: the allow list).
std::string unreachable(const DaemonHttp& at, const std::string& why);

}  // namespace drivegate::cli
