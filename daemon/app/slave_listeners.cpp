#include "slave_listeners.h"

#include <algorithm>

namespace drivegate {

namespace {

bool rtu_or_ascii(const ListenerConfig& l) { return l.framing != ListenerFraming::mbap; }

modbus_serial::Framing framing_of(const ListenerConfig& l) {
  return l.framing == ListenerFraming::ascii ? modbus_serial::Framing::ascii
                                             : modbus_serial::Framing::rtu;
}

std::shared_ptr<const slave::SlavePolicy> policy_of(const ListenerConfig& l) {
  auto p = std::make_shared<slave::SlavePolicy>();
  p->session.access = l.options.policy.access;
  p->session.word_order = l.options.policy.word_order;
  p->session.feeds_failsafe = true;  // a polling master is a PLC like a TCP one (docs/safety.md)
  if (l.serial) {
    p->session.source.kind = SourceKind::modbus_serial;
    p->session.source.listener = l.serial->port;
    p->session.source.client = l.serial->port;
  } else {
    p->session.source.kind = SourceKind::modbus_rtu_tcp;
    p->session.source.listener = l.options.name();
  }
  p->write_reply = l.write_reply;
  p->broadcast = l.broadcast;
  p->reply_timeout = l.reply_timeout;
  return p;
}

// What only a restart changes.
bool same_place(const ListenerConfig& a, const ListenerConfig& b) {
  if (a.framing != b.framing || a.ascii_timeout != b.ascii_timeout ||
      a.rx_latency != b.rx_latency) {
    return false;
  }
  if (a.serial || b.serial) {
    if (!a.serial || !b.serial) return false;
    BusConfig x = *a.serial;
    x.line = b.serial->line;  // where it is written in the file is no change
    return x == *b.serial;
  }
  return a.options.host == b.options.host && a.options.port == b.options.port;
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

SlaveListeners::~SlaveListeners() { close(); }

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
    o.host = l.options.host;
    o.port = l.options.port;
    o.allow = l.options.policy.allow;
    o.max_clients = l.options.policy.max_clients.value_or(server_.max_clients);
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

std::vector<std::string> SlaveListeners::reload(const std::vector<ListenerConfig>& listeners) {
  std::vector<std::string> restart;
  std::vector<const ListenerConfig*> next;
  for (const auto& l : listeners) {
    if (rtu_or_ascii(l)) next.push_back(&l);
  }
  std::vector<bool> matched(next.size(), false);
  const auto apply = [&](std::vector<ListenerConfig>& configs, auto& running) {
    for (std::size_t i = 0; i < configs.size(); ++i) {
      const auto it = std::find_if(next.begin(), next.end(), [&](const ListenerConfig* n) {
        return same_place(*n, configs[i]);
      });
      if (it == next.end()) {
        restart.push_back(listener_name(configs[i]) + " (removed or moved)");
        continue;
      }
      matched[static_cast<std::size_t>(it - next.begin())] = true;
      configs[i] = **it;
      if constexpr (std::is_same_v<std::decay_t<decltype(running)>,
                                   std::vector<std::shared_ptr<slave::SerialListener>>>) {
        running[i]->set_policy(policy_of(**it));
      } else {
        running[i]->set_policy(policy_of(**it), (*it)->options.policy.allow,
                               (*it)->options.policy.max_clients.value_or(server_.max_clients));
      }
    }
  };
  apply(serial_configs_, serial_);
  apply(tcp_configs_, tcp_);
  for (std::size_t i = 0; i < next.size(); ++i) {
    if (!matched[i]) restart.push_back(listener_name(*next[i]) + " (added)");
  }
  return restart;
}

void SlaveListeners::close() {
  for (const auto& l : serial_) l->close();
  for (const auto& l : tcp_) l->close();
}

}  // namespace drivegate
