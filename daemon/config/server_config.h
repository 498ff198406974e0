// The network side of the configuration: [server] (what every Modbus listener shares), the
// [[listener]] tables (address, allow list, access level, word order, TLS and roles) and [http].
// Used by config_loader.cpp only.
#pragma once

#include <toml++/toml.h>

#include "config.h"
#include "drivegate/toml_reader.h"

namespace drivegate {

// An access level's name ("read", "operate", "maintain"); nullopt with an error otherwise.
std::optional<AccessLevel> read_access(const toml::node& n, const std::string& key,
                                       Diagnostics& diag);

void read_server(const toml::table& root, Config& cfg, Diagnostics& diag);
// After read_server: [[listener]], or the single listener of [server] listen. Warns about a
// listener that lets every address write.
void read_listeners(const toml::table& root, Config& cfg, Diagnostics& diag);
// After the buses: a serial listener's port is no bus's and no other listener's.
void check_serial_listeners(const Config& cfg, Diagnostics& diag);
// [http]: address, allow list, capture. Warns when every address may reach it.
void read_http(const toml::table& root, Config& cfg, Diagnostics& diag);
// [history]: events (0..100000) and trend_seconds (0..3600).
void read_history(const toml::table& root, Config& cfg, Diagnostics& diag);

}  // namespace drivegate
