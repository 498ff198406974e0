#include "options_from_config.h"

namespace drivegate::modbus {

TlsOptions tls_options(const ListenerTlsConfig& tls) {
  return TlsOptions{.cert = tls.cert, .key = tls.key, .ca = tls.ca, .roles = tls.roles};
}

ListenerPolicy listener_policy(const ListenerPolicyConfig& policy) {
  ListenerPolicy p;
  p.allow = policy.allow;
  p.access = policy.access;
  p.word_order = policy.word_order;
  if (policy.tls) p.tls = tls_options(*policy.tls);
  p.max_clients = policy.max_clients;
  p.handshakes = policy.handshakes;
  return p;
}

std::vector<ListenerOptions> tcp_listeners(const std::vector<ListenerConfig>& listeners) {
  std::vector<ListenerOptions> out;
  for (const auto& l : listeners) {
    if (l.framing != ListenerFraming::mbap) continue;
    out.push_back(
        ListenerOptions{.host = l.host, .port = l.port, .policy = listener_policy(l.policy)});
  }
  return out;
}

ServerLimits server_limits(const ServerConfig& server) {
  return {server.max_clients, server.frame_timeout, server.idle_timeout};
}

ServerOptions server_options(const Config& config) {
  ServerOptions o;
  o.listeners = tcp_listeners(config.listeners);
  const auto limits = server_limits(config.server);
  o.max_clients = limits.max_clients;
  o.frame_timeout = limits.frame_timeout;
  o.idle_timeout = limits.idle_timeout;
  return o;
}

}  // namespace drivegate::modbus
