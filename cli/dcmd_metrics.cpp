#include "dcmd_metrics.h"

#include <charconv>
#include <cmath>
#include <cstdint>

#include "mqtt/edge_node.h"  // kCommandPoint, kCommandResult

namespace drivegate::cli {

namespace {

const sparkplug::Metric* find(const sparkplug::Payload& p, std::string_view name) {
  for (const auto& m : p.metrics) {
    if (m.name == name) return &m;
  }
  return nullptr;
}

}  // namespace

std::optional<sparkplug::Metric> command_metric(const Assignment& a, const PointSpec* point,
                                                std::string& error) {
  sparkplug::Metric m;
  m.name = a.point;
  const std::string& v = a.value;
  const char* end = v.data() + v.size();
  if (v == "true" || v == "false") {
    m.type = sparkplug::DataType::boolean;
    m.value = v == "true";
    return m;
  }
  std::int64_t whole = 0;
  if (const auto [p, ec] = std::from_chars(v.data(), end, whole); ec == std::errc{} && p == end) {
    m.type = sparkplug::DataType::int64;
    m.value = whole;
    return m;
  }
  double x = 0;
  if (const auto [p, ec] = std::from_chars(v.data(), end, x);
      ec == std::errc{} && p == end && std::isfinite(x)) {
    m.type = sparkplug::DataType::float64;
    m.value = x;
    return m;
  }
  if (point != nullptr && !point->bit_labels) {
    for (const Label& l : point->labels) {
      if (l.name == v) {
        m.type = sparkplug::DataType::int64;
        m.value = static_cast<std::int64_t>(l.value);
        return m;
      }
    }
  }
  error =
      a.point + ": '" + v + "' is not a number, true or false" +
      (point != nullptr && !point->labels.empty() && !point->bit_labels ? " or a label of the point"
                                                                        : "");
  return std::nullopt;
}

std::optional<std::string> result_of(const sparkplug::Payload& ddata, std::string_view points) {
  const auto* named = find(ddata, sparkplug::kCommandPoint);
  const auto* result = find(ddata, sparkplug::kCommandResult);
  if (named == nullptr || result == nullptr) return std::nullopt;
  const auto* n = std::get_if<std::string>(&named->value);
  const auto* r = std::get_if<std::string>(&result->value);
  if (n == nullptr || r == nullptr || *n != points) return std::nullopt;
  return *r;
}

}  // namespace drivegate::cli
