#include "modbus/slave_listeners.h"

#include <algorithm>

#include "config/config_diff.h"

namespace drivegate {

namespace {

bool rtu_or_ascii(const ListenerConfig& l) {
  return l.framing != ListenerFraming::mbap;
}

modbus_serial::Framing framing_of(const ListenerConfig& l) {
  return l.framing == ListenerFraming::ascii ? modbus_serial::Framing::ascii
                                             : modbus_serial::Framing::rtu;
}

std::shared_ptr<const slave::SlavePolicy> policy_of(const ListenerConfig& l) {
  auto p = std::make_shared<slave::SlavePolicy>();
  p->session.access = l.policy.access;
  p->session.word_order = l.policy.word_order;
  p->session.feeds_failsafe = true;  // a polling master is a PLC like a TCP one (docs/safety.md)
  if (l.serial) {
    p->session.source.kind = SourceKind::modbus_serial;
    p->session.source.listener = l.serial->port;
    p->session.source.client = l.serial->port;
  } else {
    p->session.source.kind = SourceKind::modbus_rtu_tcp;
    p->session.source.listener = net::listen_name(l.host, l.port, l.policy.tls.has_value());
  }
  p->write_reply = l.write_reply;
  p->broadcast = l.broadcast;
  p->reply_timeout = l.reply_timeout;
  return p;
}

}  // namespace

SlaveListeners::SlaveListeners(boost::asio::io_context& io, net::Clock& clock,
                               modbus::Backend& backend, modbus::DeviceIdentity identity,
                               ServerConfig server, std::shared_ptr<spdlog::logger> log)
    : io_(io),
      clock_(clock),
      backend_(backend),
      identity_(std::move(identity)),
      server_(server),
      log_(std::move(log)) {}

SlaveListeners::~SlaveListeners() {
  close();
}

bool SlaveListeners::start(const std::vector<ListenerConfig>& listeners) {
  for (const auto& l : listeners) {
    if (!rtu_or_ascii(l)) continue;
    if (l.serial) {
      slave::SerialListenerOptions o;
      o.line = *l.serial;
      o.framing = framing_of(l);
      o.ascii_timeout = l.ascii_timeout;
      o.latency = l.rx_latency;
      o.identity = identity_;
      auto s = std::make_shared<slave::SerialListener>(io_, clock_, backend_, std::move(o),
                                                       policy_of(l), log_);
      s->start();
      serial_.push_back(std::move(s));
      serial_configs_.push_back(l);
      continue;
    }
    slave::RtuTcpOptions o;
    o.host = l.host;
    o.port = l.port;
    o.allow = l.policy.allow;
    o.max_clients = l.policy.max_clients.value_or(server_.max_clients);
    o.idle_timeout = server_.idle_timeout;
    o.frame_timeout = server_.frame_timeout;
    o.framing = framing_of(l);
    o.identity = identity_;
    auto t = std::make_shared<slave::RtuTcpListener>(io_, clock_, backend_, std::move(o),
                                                     policy_of(l), log_);
    if (t->listen()) return false;
    tcp_.push_back(std::move(t));
    tcp_configs_.push_back(l);
  }
  return true;
}

void SlaveListeners::reload(const std::vector<ListenerConfig>& listeners) {
  std::vector<const ListenerConfig*> next;
  for (const auto& l : listeners) {
    if (rtu_or_ascii(l)) next.push_back(&l);
  }
  const auto apply = [&](std::vector<ListenerConfig>& configs, auto& running) {
    for (std::size_t i = 0; i < configs.size(); ++i) {
      const auto it = std::find_if(next.begin(), next.end(), [&](const ListenerConfig* n) {
        return same_place(*n, configs[i]);
      });
      if (it == next.end()) continue;  // waits for a restart (plan_reload says so)
      configs[i] = **it;
      if constexpr (std::is_same_v<std::decay_t<decltype(running)>,
                                   std::vector<std::shared_ptr<slave::SerialListener>>>) {
        running[i]->set_policy(policy_of(**it));
      } else {
        running[i]->set_policy(policy_of(**it), (*it)->policy.allow,
                               (*it)->policy.max_clients.value_or(server_.max_clients));
      }
    }
  };
  apply(serial_configs_, serial_);
  apply(tcp_configs_, tcp_);
}

void SlaveListeners::close() {
  for (const auto& l : serial_) l->close();
  for (const auto& l : tcp_) l->close();
}

}  // namespace drivegate
