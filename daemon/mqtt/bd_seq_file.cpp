#include "mqtt/bd_seq_file.h"

#include <fcntl.h>
#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstring>

#include "base/read_file.h"
#include "base/state_file.h"

namespace drivegate::mqtt {

namespace {
constexpr std::size_t kMaxFile = 64;  // "255\n" and then some: anything longer is not ours
constexpr std::string_view kPrefix = "sparkplug-";
}  // namespace

BdSeqFile::BdSeqFile(const std::filesystem::path& state_dir, std::string_view group,
                     std::string_view edge_node) {
  if (state_dir.empty()) return;
  path_ = edge_node_state_path(state_dir, group, edge_node, ".bdseq");
}

std::filesystem::path edge_node_state_path(const std::filesystem::path& dir, std::string_view group,
                                           std::string_view edge_node, std::string_view extension) {
  return dir / (std::string(kPrefix) + std::string(group) + "-" + std::string(edge_node) +
                std::string(extension));
}

std::vector<std::filesystem::path> other_edge_node_state(const std::filesystem::path& own) {
  const std::string extension = own.extension().string();
  std::vector<std::filesystem::path> out;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(own.parent_path(), ec)) {
    const std::string name = entry.path().filename().string();
    if (name.size() > kPrefix.size() + extension.size() && name.starts_with(kPrefix) &&
        name.ends_with(extension) && entry.path() != own) {
      out.push_back(entry.path());
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::optional<std::uint8_t> BdSeqFile::load(std::string& error) const {
  error.clear();
  if (path_.empty()) return std::nullopt;
  struct stat st {};
  if (::lstat(path_.c_str(), &st) != 0) {  // the name itself: a link is not followed
    if (errno != ENOENT) error = path_.string() + ": " + std::strerror(errno);
    return std::nullopt;  // ENOENT: the first start with this edge node id
  }
  if (!S_ISREG(st.st_mode)) {
    // A FIFO, a link, a directory: never opened, and moved out of the way of the next save.
    std::string why;
    const auto aside = set_aside(AT_FDCWD, path_.string(), why);
    error = path_.string() + ": " + file_kind(st.st_mode) + ", not a regular file; " +
            (aside ? "set aside as " + *aside : why);
    return std::nullopt;
  }
  const auto text = read_regular_file(path_, kMaxFile, error, Links::refuse);
  if (!text) return std::nullopt;
  const auto n = parse_bd_seq(*text);
  if (!n) error = path_.string() + ": not a bdSeq (a number 0..255)";
  return n;
}

std::error_code BdSeqFile::save(std::uint8_t bd_seq) const {
  if (path_.empty()) return {};
  const std::string text = std::to_string(bd_seq) + "\n";
  auto ec = replace_file(path_, text);
  if (ec == std::errc::no_such_file_or_directory) {
    // The state directory was removed while the daemon ran: made again (as StateDirectory= had).
    std::error_code made;
    std::filesystem::create_directories(path_.parent_path(), made);
    if (!made) ec = replace_file(path_, text);
  }
  return ec;
}

std::optional<std::uint8_t> parse_bd_seq(std::string_view text) {
  if (text.ends_with('\n')) text.remove_suffix(1);
  if (text.empty() || text.size() > 3) return std::nullopt;
  unsigned n = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), n);
  if (ec != std::errc{} || end != text.data() + text.size() || n > 255) return std::nullopt;
  return static_cast<std::uint8_t>(n);
}

}  // namespace drivegate::mqtt
