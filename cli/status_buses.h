// The names of the buses the running daemon has, read from its status JSON (/api/v1/status,
// docs/http.md: "buses": [{"name": ...}, ...]), so that a refusal naming a bus the daemon does
// not have can say which ones it does have.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace drivegate::cli {

// nullopt when `json` is not a JSON object with a "buses" array of objects named by "name".
std::optional<std::vector<std::string>> bus_names(std::string_view json);

}  // namespace drivegate::cli
