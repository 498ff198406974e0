// The Modbus TCP server's options made from the configuration's plain data: [server] and the
// Modbus TCP (MBAP) [[listener]]s, their policies and TLS files. The configuration knows nothing
// of the server; the server takes its settings from it here, at start and at every reload.
#pragma once

#include <vector>

#include "config/config.h"
#include "server_options.h"

namespace drivegate::modbus {

TlsOptions tls_options(const ListenerTlsConfig& tls);
ListenerPolicy listener_policy(const ListenerPolicyConfig& policy);
// The Modbus TCP listeners among the configuration's, in its order (RTU / ASCII ones are the
// serial slave's).
std::vector<ListenerOptions> tcp_listeners(const std::vector<ListenerConfig>& listeners);
ServerLimits server_limits(const ServerConfig& server);
// Everything but the identity, which is the daemon's to say.
ServerOptions server_options(const Config& config);

}  // namespace drivegate::modbus
