#include "settings.h"

#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>

#include "description_parser.h"

namespace drivegate::framed {
namespace {

struct ShippedDescription {
  std::string_view name;
  std::string_view text;
};

#include "shipped_protocols.inc"

// A regular file's text, at most kMaxDescriptionBytes; nullopt and `error` otherwise.
std::optional<std::string> read_file(const std::filesystem::path& path, std::string& error) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    error = path.string() + " is not a regular file";
    return std::nullopt;
  }
  if (std::filesystem::file_size(path, ec) > kMaxDescriptionBytes) {
    error = path.string() + " is larger than " + std::to_string(kMaxDescriptionBytes) + " bytes";
    return std::nullopt;
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    error = "cannot read " + path.string();
    return std::nullopt;
  }
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

std::vector<std::string_view> shipped_names() {
  std::vector<std::string_view> out;
  out.reserve(std::size(kShippedProtocols));
  for (const auto& s : kShippedProtocols) out.push_back(s.name);
  return out;
}

std::optional<std::string_view> shipped_text(std::string_view name) {
  for (const auto& s : kShippedProtocols) {
    if (s.name == name) return s.text;
  }
  return std::nullopt;
}

std::optional<DescriptionText> find_description(const std::string& name_or_path,
                                                std::string& error) {
  if (name_or_path.empty()) {
    error = "required: a description's name (" + [] {
      std::string names;
      for (const auto n : shipped_names()) names += (names.empty() ? "" : ", ") + std::string(n);
      return names;
    }() + " are shipped) or a file's path";
    return std::nullopt;
  }
  if (name_or_path.find('/') != std::string::npos || name_or_path.ends_with(".toml")) {
    auto text = read_file(name_or_path, error);
    if (!text) return std::nullopt;
    return DescriptionText{std::move(*text), name_or_path};
  }
  if (!valid_protocol_name(name_or_path)) {
    error =
        "'" + name_or_path + "' is neither a description's name (a-z, 0-9, '-', '_') nor a path";
    return std::nullopt;
  }
  for (const char* dir : kProtocolDirs) {
    const std::filesystem::path file = std::filesystem::path(dir) / (name_or_path + ".toml");
    std::error_code ec;
    if (!std::filesystem::exists(file, ec)) continue;
    auto text = read_file(file, error);
    if (!text) return std::nullopt;
    return DescriptionText{std::move(*text), file.string()};
  }
  if (const auto text = shipped_text(name_or_path)) {
    return DescriptionText{std::string(*text), "shipped " + name_or_path};
  }
  error = "no description '" + name_or_path + "' in " + kProtocolDirs[0] + " or " +
          kProtocolDirs[1] + ", and none shipped by that name";
  return std::nullopt;
}

std::shared_ptr<const Description> load_description(const std::string& protocol,
                                                    std::string& error) {
  auto text = find_description(protocol, error);
  if (!text) {
    error = "option protocol: " + error;
    return nullptr;
  }
  // The same text is the same description: a device's driver, its simulator and its specialised
  // descriptor share one, and a reload with the file unchanged finds the one it had.
  static std::mutex mutex;
  static std::map<std::pair<std::string, std::string>, std::shared_ptr<const Description>> cache;
  const std::lock_guard lock(mutex);
  const auto key = std::make_pair(text->source, text->text);
  if (const auto it = cache.find(key); it != cache.end()) return it->second;
  auto parsed = parse_description(text->text, text->source);
  if (auto* errors = std::get_if<std::vector<std::string>>(&parsed)) {
    // Every error, so the description is fixed in one pass; one line, as a factory's error is.
    error = "option protocol:";
    for (std::size_t i = 0; i < errors->size(); ++i) error += (i == 0 ? " " : "; ") + (*errors)[i];
    return nullptr;
  }
  auto d = std::get<std::shared_ptr<const Description>>(std::move(parsed));
  cache.emplace(key, d);
  return d;
}

}  // namespace drivegate::framed
