#include "status_buses.h"

#include "json_reader.h"

namespace drivegate::cli {
namespace {

// One element of "buses": an object; its "name", the other members passed over.
std::optional<std::string> bus_name(Reader& r) {
  if (!r.at('{')) return std::nullopt;
  std::optional<std::string> name;
  if (r.at('}')) return std::nullopt;
  do {
    const auto key = r.string();
    if (!key || !r.at(':')) return std::nullopt;
    if (*key == "name" && r.peek('"')) {
      name = r.string();
      if (!name) return std::nullopt;
    } else if (!r.skip()) {
      return std::nullopt;
    }
  } while (r.at(','));
  if (!r.at('}')) return std::nullopt;
  return name;
}

}  // namespace

std::optional<std::vector<std::string>> bus_names(std::string_view json) {
  Reader r(json);
  if (!r.at('{') || r.at('}')) return std::nullopt;
  do {
    const auto key = r.string();
    if (!key || !r.at(':')) return std::nullopt;
    if (*key != "buses") {
      if (!r.skip()) return std::nullopt;
      continue;
    }
    if (!r.at('[')) return std::nullopt;
    std::vector<std::string> names;
    if (r.at(']')) return names;
    do {
      auto name = bus_name(r);
      if (!name) return std::nullopt;
      names.push_back(std::move(*name));
    } while (r.at(','));
    if (!r.at(']')) return std::nullopt;
    return names;
  } while (r.at(','));
  return std::nullopt;
}

}  // namespace drivegate::cli
