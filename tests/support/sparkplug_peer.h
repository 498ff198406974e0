// End-to-end test support: an independent Sparkplug B 3.0 peer on the MQTT broker, to check what
// drivegate's northbound really puts on the wire. It runs tests/mqtt/peer/sparkplug_peer.js
// (Node.js) and reads its line protocol (described at the top of that file).
//
// Why independent: the peer decodes with Eclipse Tahu's schema and encoder from npm
// (`sparkplug-payload`) and talks MQTT with MQTT.js; nothing of drivegate's daemon/mqtt or proto/
// is involved, so a mistake there cannot cancel itself out in the test. tools/deps.sh installs
// node and the peer's node_modules (npm ci).
//
//   drivegate::test::Broker broker(dir);
//   drivegate::test::SparkplugPeer host(broker.port());             // subscribes to spBv1.0/#
//   auto birth = host.wait_for([](const auto& m) { return m.message_type() == "NBIRTH"; },
//                              std::chrono::seconds(10));
//   EXPECT_EQ(birth->metric("bdSeq")->type, "UInt64");
//   host.publish("spBv1.0/g/NCMD/edge",
//                R"({"metrics":[{"name":"Node Control/Rebirth","type":"Boolean","value":true}]})");
//   host.publish_text("spBv1.0/STATE/host", R"({"online":true,"timestamp":1700000000000})",
//                     true, 1);
//
// Metric values are the peer's text: decimal numbers (64-bit exact), true/false, "null",
// arrays "[a,b]", bytes in hex. In NDATA/DDATA a metric sent by alias only gets its name and
// datatype from the last birth (Metric::from_birth_name() / from_birth_type() tell).
#pragma once

#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <deque>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "e2e.h"

#ifndef DRIVEGATE_TEST_PEER_DIR
#define DRIVEGATE_TEST_PEER_DIR \
  (std::filesystem::path(__FILE__).parent_path().parent_path() / "mqtt" / "peer")
#endif

namespace drivegate::test {

// A Sparkplug 3.0 primary host's STATE payload: {"online":true|false,"timestamp":MS}.
inline std::string host_state(bool online, std::uint64_t timestamp_ms) {
  return std::string(R"({"online":)") + (online ? "true" : "false") + R"(,"timestamp":)" +
         std::to_string(timestamp_ms) + "}";
}

inline std::filesystem::path peer_dir() {
  return DRIVEGATE_TEST_PEER_DIR;
}

namespace sparkplug_detail {

// Splits on TAB.
inline std::vector<std::string> fields(const std::string& line) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (true) {
    const auto tab = line.find('\t', start);
    out.push_back(line.substr(start, tab == std::string::npos ? std::string::npos : tab - start));
    if (tab == std::string::npos) return out;
    start = tab + 1;
  }
}

// \\ \t \n \r back to their characters; any other escaped character stands for itself.
inline std::string unescape(std::string_view s) {
  std::string out;
  out.reserve(s.size());
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i] != '\\' || i + 1 == s.size()) {
      out.push_back(s[i]);
      continue;
    }
    const char c = s[++i];
    out.push_back(c == 't' ? '\t' : c == 'n' ? '\n' : c == 'r' ? '\r' : c);
  }
  return out;
}

// Splits escaped text on `sep` where it is not escaped; the parts stay escaped.
inline std::vector<std::string> split_escaped(std::string_view s, char sep, std::size_t max = 0) {
  std::vector<std::string> out(1);
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '\\' && i + 1 < s.size()) {
      out.back() += s.substr(i, 2);
      ++i;
    } else if (s[i] == sep && (max == 0 || out.size() < max)) {
      out.emplace_back();
    } else {
      out.back() += s[i];
    }
  }
  return out;
}

inline std::optional<std::uint64_t> number(const std::string& s) {
  if (s.empty() || s == "-") return std::nullopt;
  return std::stoull(s);
}

inline std::string escape(std::string_view s) {
  std::string out;
  for (const char c : s) {
    switch (c) {
      case '\\':
        out += "\\\\";
        break;
      case '\t':
        out += "\\t";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\r':
        out += "\\r";
        break;
      default:
        out += c;
    }
  }
  return out;
}

}  // namespace sparkplug_detail

struct Metric {
  std::string name;  // "" when neither on the wire nor known from the birth
  std::optional<std::uint64_t> alias;
  std::string type;   // Sparkplug datatype name: Int16, UInt64, Float, ...; ""
  std::string value;  // unescaped; "null" for is_null
  std::map<std::string, std::string> properties;  // e.g. engUnit -> rpm
  std::string field;                       // the protobuf value field on the wire: int_value, ...
  std::optional<std::uint64_t> timestamp;  // the metric's own timestamp
  std::vector<std::string> flags;  // name_from_birth, type_from_birth, historical, transient

  [[nodiscard]] bool has_flag(std::string_view f) const {
    for (const auto& x : flags) {
      if (x == f) return true;
    }
    return false;
  }
  // Sent by alias only: the name came from the birth certificate.
  [[nodiscard]] bool from_birth_name() const { return has_flag("name_from_birth"); }
  [[nodiscard]] bool from_birth_type() const { return has_flag("type_from_birth"); }
  [[nodiscard]] bool is_null() const { return value == "null" && field.empty(); }
  [[nodiscard]] double as_double() const { return std::stod(value); }
  [[nodiscard]] std::int64_t as_int() const { return std::stoll(value); }
  [[nodiscard]] std::uint64_t as_uint() const { return std::stoull(value); }
};

struct Message {
  // "msg" (a Sparkplug payload), "text" (STATE, other topics), "error" (did not decode),
  // "disconnected" / "reconnected" (the peer lost / got back the broker).
  std::string kind;
  std::string topic;
  std::optional<std::uint64_t> seq;
  std::optional<std::uint64_t> timestamp;
  bool retain = false;
  double received_unix = 0;  // when the peer received it (unix seconds, microseconds)
  std::vector<Metric> metrics;
  std::string text;  // "text": the payload; "error": the decoder's message

  [[nodiscard]] const Metric* metric(std::string_view name) const {
    for (const auto& m : metrics) {
      if (m.name == name) return &m;
    }
    return nullptr;
  }
  [[nodiscard]] const Metric* metric_by_alias(std::uint64_t alias) const {
    for (const auto& m : metrics) {
      if (m.alias == alias) return &m;
    }
    return nullptr;
  }
  // NBIRTH, NDEATH, DBIRTH, DDEATH, NDATA, DDATA, NCMD, DCMD, STATE; "" otherwise.
  [[nodiscard]] std::string message_type() const {
    const auto l = levels();
    if (l.size() < 3 || l[0] != "spBv1.0") return "";
    if (l[1] == "STATE") return "STATE";
    return l[2];
  }
  [[nodiscard]] std::string group() const { return level(1); }
  [[nodiscard]] std::string node() const { return message_type() == "STATE" ? "" : level(3); }
  // The device id, the 5th topic level, or "".
  [[nodiscard]] std::string device() const { return message_type() == "STATE" ? "" : level(4); }

 private:
  [[nodiscard]] std::vector<std::string> levels() const {
    std::vector<std::string> out(1);
    for (const char c : topic) {
      if (c == '/') {
        out.emplace_back();
      } else {
        out.back() += c;
      }
    }
    return out;
  }
  [[nodiscard]] std::string level(std::size_t i) const {
    const auto l = levels();
    return i < l.size() ? l[i] : "";
  }
};

class SparkplugPeer {
 public:
  struct Options {
    std::string broker;  // URL; empty: mqtt://127.0.0.1:port
    std::vector<std::string> subscriptions = {"spBv1.0/#"};
    std::string client_id;                // empty: sparkplug-peer-<pid>
    std::filesystem::path ca, cert, key;  // for mqtts://
    std::filesystem::path stderr_file;    // empty: the test's stderr
    std::vector<std::string> extra_args;  // e.g. {"--mqtt5"}, a will
    std::chrono::milliseconds ready_timeout = std::chrono::seconds(10);
  };

  explicit SparkplugPeer(int port) : SparkplugPeer(port, Options{}) {}
  SparkplugPeer(int port, Options options) : child_(argv(port, options), options.stderr_file) {
    const auto deadline = std::chrono::steady_clock::now() + options.ready_timeout;
    while (true) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          deadline - std::chrono::steady_clock::now());
      const auto line = left.count() > 0 ? child_.read_line(left) : std::nullopt;
      if (!line) {
        throw std::runtime_error("the Sparkplug peer (" + script().string() +
                                 ") did not get ready: no broker, or node/npm ci missing? "
                                 "(tools/deps.sh)");
      }
      if (*line == "ready") return;
    }
  }
  SparkplugPeer(const SparkplugPeer&) = delete;
  SparkplugPeer& operator=(const SparkplugPeer&) = delete;

  static std::filesystem::path script() { return peer_dir() / "sparkplug_peer.js"; }

  // The next message (in order), or nullopt after `timeout`.
  std::optional<Message> next(std::chrono::milliseconds timeout) {
    if (!pending_.empty()) {
      Message m = std::move(pending_.front());
      pending_.pop_front();
      return m;
    }
    return read_message(std::chrono::steady_clock::now() + timeout);
  }

  // The first message from now on for which `pred` holds, skipping the others (all of them stay
  // in history()); nullopt after `timeout`.
  std::optional<Message> wait_for(const std::function<bool(const Message&)>& pred,
                                  std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (true) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          deadline - std::chrono::steady_clock::now());
      auto m = next(std::max(left, std::chrono::milliseconds(0)));
      if (!m) return std::nullopt;
      if (pred(*m)) return m;
    }
  }
  // wait_for a Sparkplug message type (NBIRTH, DDATA, ...), optionally of one device.
  std::optional<Message> wait_for_type(std::string_view type, std::chrono::milliseconds timeout,
                                       std::optional<std::string> device = std::nullopt) {
    return wait_for(
        [&](const Message& m) {
          return m.message_type() == type && (!device || m.device() == *device);
        },
        timeout);
  }

  // Every message received so far, in order, whether next()/wait_for() returned it or not.
  [[nodiscard]] const std::vector<Message>& history() const { return history_; }
  void clear_history() { history_.clear(); }

  // Encodes `json` with Tahu's encodePayload and publishes it (QoS 0, not retained); waits for
  // the peer's acknowledgement. 64-bit values may be JSON strings ("18446744073709551615").
  void publish(const std::string& topic, const std::string& json) {
    command("publish\t" + topic + "\t" + json, topic);
  }
  // The same, retained by the broker (what a broken host might leave there).
  void publish_retained(const std::string& topic, const std::string& json) {
    command("publish_retained\t" + topic + "\t" + json, topic);
  }
  // `count` times back to back (a flood); returns once the last one is sent.
  void publish_repeat(const std::string& topic, const std::string& json, int count) {
    command("publish_repeat\t" + topic + "\t" + std::to_string(count) + "\t" + json, topic);
  }
  // Publishes raw text (e.g. a STATE message).
  void publish_text(const std::string& topic, const std::string& text, bool retain = false,
                    int qos = 0) {
    command("publish_text\t" + topic + "\t" + sparkplug_detail::escape(text) + "\t" +
                (retain ? "1" : "0") + "\t" + std::to_string(qos),
            topic);
  }
  // Publishes raw bytes given in hex (e.g. a payload that is not Sparkplug).
  void publish_hex(const std::string& topic, const std::string& hex, bool retain = false,
                   int qos = 0) {
    command("publish_hex\t" + topic + "\t" + hex + "\t" + (retain ? "1" : "0") + "\t" +
                std::to_string(qos),
            topic);
  }

  Child& process() { return child_; }

 private:
  static std::vector<std::string> argv(int port, const Options& o) {
    // posix_spawn does not search PATH: env does.
    std::vector<std::string> a = {
        "/usr/bin/env", "node", script().string(), "--broker",
        o.broker.empty() ? "mqtt://127.0.0.1:" + std::to_string(port) : o.broker};
    for (const auto& s : o.subscriptions) {
      a.emplace_back("--sub");
      a.push_back(s);
    }
    if (!o.client_id.empty()) a.insert(a.end(), {"--client-id", o.client_id});
    if (!o.ca.empty()) a.insert(a.end(), {"--ca", o.ca.string()});
    if (!o.cert.empty()) a.insert(a.end(), {"--cert", o.cert.string()});
    if (!o.key.empty()) a.insert(a.end(), {"--key", o.key.string()});
    a.insert(a.end(), o.extra_args.begin(), o.extra_args.end());
    return a;
  }

  void command(const std::string& line, const std::string& topic) {
    child_.write_line(line);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (true) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          deadline - std::chrono::steady_clock::now());
      const auto l = left.count() > 0 ? child_.read_line(left) : std::nullopt;
      if (!l) throw std::runtime_error("the Sparkplug peer did not publish on " + topic);
      auto f = sparkplug_detail::fields(*l);
      if (f[0] == "published" && f.size() > 1 && f[1] == topic) return;
      if (f[0] == "publish_failed" && f.size() > 1 && f[1] == topic) {
        throw std::runtime_error("the Sparkplug peer could not publish on " + topic + ": " +
                                 sparkplug_detail::unescape(f.size() > 2 ? f[2] : ""));
      }
      if (auto m = parse(*l, deadline)) pending_.push_back(std::move(*m));
    }
  }

  std::optional<Message> read_message(std::chrono::steady_clock::time_point deadline) {
    while (true) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0) return std::nullopt;
      const auto line = child_.read_line(left);
      if (!line) return std::nullopt;
      if (auto m = parse(*line, deadline)) return m;
    }
  }

  // One event from its first line (and, for "msg", the lines up to "end"); nullopt for lines
  // that are not messages (e.g. a stray "published").
  std::optional<Message> parse(const std::string& line,
                               std::chrono::steady_clock::time_point deadline) {
    using namespace sparkplug_detail;
    const auto f = fields(line);
    Message m;
    m.kind = f[0];
    if (m.kind == "disconnected" || m.kind == "reconnected") {
      history_.push_back(m);
      return m;
    }
    if (m.kind == "text" && f.size() >= 4) {
      m.topic = f[1];
      m.retain = f[2] == "1";
      m.text = unescape(f[3]);
    } else if (m.kind == "error" && f.size() >= 3) {
      m.topic = f[1];
      m.text = unescape(f[2]);
    } else if (m.kind == "msg" && f.size() >= 7) {
      m.topic = f[1];
      m.seq = number(f[2]);
      m.timestamp = number(f[3]);
      m.retain = f[4] == "1";
      m.received_unix = std::stod(f[5]);
      // The metric lines follow at once (one write); allow at least a second for them anyway.
      const auto body_deadline =
          std::max(deadline, std::chrono::steady_clock::now() + std::chrono::seconds(1));
      while (true) {
        const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
            body_deadline - std::chrono::steady_clock::now());
        const auto l = child_.read_line(std::max(left, std::chrono::milliseconds(1)));
        if (!l) throw std::runtime_error("the Sparkplug peer cut a message short: " + line);
        if (*l == "end") break;
        const auto g = fields(*l);
        if (g[0] != "metric" || g.size() < 9) {
          throw std::runtime_error("the Sparkplug peer printed an unexpected line: " + *l);
        }
        Metric metric;
        metric.name = g[1] == "-" ? "" : unescape(g[1]);
        metric.alias = number(g[2]);
        metric.type = g[3] == "-" ? "" : g[3];
        metric.value = unescape(g[4]);
        if (g[5] != "-") {
          for (const auto& kv : split_escaped(g[5], ';')) {
            const auto p = split_escaped(kv, '=', 2);
            metric.properties[unescape(p[0])] = p.size() > 1 ? unescape(p[1]) : "";
          }
        }
        metric.field = g[6] == "-" ? "" : g[6];
        metric.timestamp = number(g[7]);
        if (g[8] != "-") metric.flags = split_escaped(g[8], ',');
        m.metrics.push_back(std::move(metric));
      }
    } else {
      return std::nullopt;
    }
    history_.push_back(m);
    return m;
  }

  Child child_;
  std::deque<Message> pending_;
  std::vector<Message> history_;
};

}  // namespace drivegate::test
