#include "routes.h"

#include <algorithm>
#include <charconv>
#include <cstdint>

namespace drivegate::http {

namespace {
constexpr const char* kJson = "application/json";
// Prometheus text exposition format, version 0.0.4.
constexpr const char* kPrometheus = "text/plain; version=0.0.4; charset=utf-8";

constexpr const char* kText = "text/plain; charset=utf-8";
constexpr const char* kPcap = "application/vnd.tcpdump.pcap";

std::string_view path_of(std::string_view target) {
  return target.substr(0, target.find('?'));
}

int hex_digit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

// %XX and '+' decoded; nullopt for a broken escape.
std::optional<std::string> unescape(std::string_view v) {
  std::string out;
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (v[i] == '+') {
      out.push_back(' ');
    } else if (v[i] == '%') {
      if (i + 2 >= v.size()) return std::nullopt;
      const int hi = hex_digit(v[i + 1]);
      const int lo = hex_digit(v[i + 2]);
      if (hi < 0 || lo < 0) return std::nullopt;
      out.push_back(static_cast<char>(hi * 16 + lo));
      i += 2;
    } else {
      out.push_back(v[i]);
    }
  }
  return out;
}

// The value of query parameter `key` (the first), decoded; nullopt when absent.
std::optional<std::string> query_value(std::string_view target, std::string_view key) {
  const auto q = target.find('?');
  if (q == std::string_view::npos) return std::nullopt;
  std::string_view rest = target.substr(q + 1);
  while (!rest.empty()) {
    const auto amp = rest.find('&');
    const std::string_view pair = rest.substr(0, amp);
    rest = amp == std::string_view::npos ? std::string_view{} : rest.substr(amp + 1);
    const auto eq = pair.find('=');
    if (pair.substr(0, eq) != key) continue;
    if (eq == std::string_view::npos) return std::string();
    // A broken escape reads as empty: refused like a missing value.
    return unescape(pair.substr(eq + 1)).value_or(std::string());
  }
  return std::nullopt;
}

// Whether every value in the query decodes: a broken %-escape is a 400, never a value read as
// empty (?device=%zz meant a device, not "any device").
bool query_decodes(std::string_view target) {
  const auto q = target.find('?');
  if (q == std::string_view::npos) return true;
  std::string_view rest = target.substr(q + 1);
  while (!rest.empty()) {
    const auto amp = rest.find('&');
    const std::string_view pair = rest.substr(0, amp);
    rest = amp == std::string_view::npos ? std::string_view{} : rest.substr(amp + 1);
    const auto eq = pair.find('=');
    if (eq != std::string_view::npos && !unescape(pair.substr(eq + 1))) return false;
  }
  return true;
}

const char* const kBadEscape = "a query value has a broken %-escape\n";

// ?since=UNIX_SECONDS (a fraction allowed) as milliseconds; nullopt if it is not a number of
// seconds between the epoch and the year 5000 (anything later would overflow the milliseconds).
std::optional<std::int64_t> since_ms(std::string_view target) {
  const auto v = query_value(target, "since");
  if (!v) return 0;
  double seconds = 0;
  const auto [end, ec] = std::from_chars(v->data(), v->data() + v->size(), seconds,
                                         std::chars_format::fixed);
  if (v->empty() || ec != std::errc{} || end != v->data() + v->size() || !(seconds >= 0) ||
      seconds > 1e11) {
    return std::nullopt;
  }
  return static_cast<std::int64_t>(seconds * 1000.0);
}

// A whole number 0..max, nullopt if it is not one.
std::optional<std::uint64_t> whole(const std::string& v, std::uint64_t max) {
  if (v.empty() || v.size() > 19 || v.find_first_not_of("0123456789") != std::string::npos) {
    return std::nullopt;
  }
  const std::uint64_t n = std::stoull(v);
  if (n > max) return std::nullopt;
  return n;
}

Response events_route(std::string_view target, Content& content) {
  if (!query_decodes(target)) return {400, kText, kBadEscape, {}, {}, {}};
  EventsQuery q;
  q.device = query_value(target, "device").value_or("");
  q.kind = query_value(target, "kind").value_or("");
  const auto since = since_ms(target);
  if (!since) return {400, kText, "since must be seconds since the epoch\n", {}, {}, {}};
  q.since_ms = *since;
  if (const auto after = query_value(target, "after")) {
    const auto n = whole(*after, UINT64_MAX / 2);
    if (!n) return {400, kText, "after must be a sequence number\n", {}, {}, {}};
    q.after = *n;
  }
  if (const auto limit = query_value(target, "limit")) {
    // The history returns at most its own maximum however many are asked for.
    const auto n = whole(*limit, UINT32_MAX);
    if (!n || *n == 0) return {400, kText, "limit must be a whole number above 0\n", {}, {}, {}};
    q.limit = *n;
  }
  auto page = content.events_page(q);
  if (!page) return {400, kText, "no such kind of event\n", {}, {}, {}};
  return {200, kJson, {}, {}, {}, std::move(page)};
}

Response trends_route(std::string_view target, Content& content) {
  if (!query_decodes(target)) return {400, kText, kBadEscape, {}, {}, {}};
  TrendsQuery q;
  const auto device = query_value(target, "device");
  const auto bus = query_value(target, "bus");
  if (device && bus) return {400, kText, "device or bus, not both\n", {}, {}, {}};
  if (device) q.name = "device:" + *device;
  if (bus) q.name = "bus:" + *bus;
  const auto since = since_ms(target);
  if (!since) return {400, kText, "since must be seconds since the epoch\n", {}, {}, {}};
  q.since_ms = *since;
  return {200, kJson, content.trends_json(q), {}, {}, {}};
}

Response capture_route(std::string_view target, Content& content, const RouteOptions& options) {
  if (!options.capture) {
    return {403, kText, "capture is not enabled ([http] capture = true)\n", {}, {}, {}};
  }
  const auto bus = query_value(target, "bus");
  if (!bus || bus->empty()) return {400, kText, "capture needs ?bus=NAME\n", {}, {}, {}};
  CaptureRequest req{*bus, kCaptureDefault};
  if (const auto seconds = query_value(target, "seconds")) {
    const auto& t = *seconds;
    long n = 0;
    const bool digits =
        !t.empty() && t.size() <= 4 && t.find_first_not_of("0123456789") == std::string::npos;
    if (digits) n = std::stol(t);
    if (!digits || n < 1 || n > kCaptureMax.count()) {
      return {400, kText, "seconds must be 1.." + std::to_string(kCaptureMax.count()) + "\n", {},
              {}, {}};
    }
    req.duration = std::chrono::seconds(n);
  }
  if (!content.has_bus(req.bus)) return {404, kText, "no such bus\n", {}, {}, {}};
  return {200, kPcap, {}, {}, std::move(req), {}};
}
}  // namespace

Response route(std::string_view method, std::string_view target, Content& content,
               const RouteOptions& options) {
  if (method != "GET" && method != "HEAD") {
    return {405,
            "text/plain; charset=utf-8",
            "only GET and HEAD are served: this is read-only\n",
            "GET, HEAD",
            {},
            {}};
  }
  const std::string_view path = path_of(target);
  if (path == "/" || path == "/index.html") {
    return {200, "text/html; charset=utf-8", std::string(status_page()), {}, {}, {}};
  }
  if (path == "/api/v1/status") return {200, kJson, content.status_json(), {}, {}, {}};
  if (path == "/api/v1/regmap") return {200, kJson, content.regmap_json(), {}, {}, {}};
  if (path == "/metrics") return {200, kPrometheus, content.metrics(), {}, {}, {}};
  if (path == "/api/v1/capture") return capture_route(target, content, options);
  if (path == "/api/v1/events") return events_route(target, content);
  if (path == "/api/v1/trends") return trends_route(target, content);
  return {404, "text/plain; charset=utf-8", "not found\n", {}, {}, {}};
}

}  // namespace drivegate::http
