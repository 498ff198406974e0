#include "routes.h"

namespace drivegate::http {

namespace {
constexpr const char* kJson = "application/json";
// Prometheus text exposition format, version 0.0.4.
constexpr const char* kPrometheus = "text/plain; version=0.0.4; charset=utf-8";

std::string_view path_of(std::string_view target) {
  return target.substr(0, target.find('?'));
}
}  // namespace

Response route(std::string_view method, std::string_view target, Content& content) {
  if (method != "GET" && method != "HEAD") {
    return {405, "text/plain; charset=utf-8", "only GET and HEAD are served: this is read-only\n",
            "GET, HEAD"};
  }
  const std::string_view path = path_of(target);
  if (path == "/" || path == "/index.html") {
    return {200, "text/html; charset=utf-8", std::string(status_page()), {}};
  }
  if (path == "/api/v1/status") return {200, kJson, content.status_json(), {}};
  if (path == "/api/v1/regmap") return {200, kJson, content.regmap_json(), {}};
  if (path == "/metrics") return {200, kPrometheus, content.metrics(), {}};
  return {404, "text/plain; charset=utf-8", "not found\n", {}};
}

}  // namespace drivegate::http
