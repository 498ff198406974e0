// Small facts the daemon keeps across restarts (the Sparkplug bdSeq, docs/mqtt.md), each in its
// own file under the state directory (systemd's StateDirectory=, /var/lib/drivegate). A file is
// replaced whole or not at all: the new content goes to a temporary file beside it, which is
// synced and then renamed over the old one, and the directory synced after the rename, so a power
// cut leaves either the old content or the new, never a mix or an empty file.
#pragma once

#include <filesystem>
#include <string_view>
#include <system_error>

namespace drivegate {

// Replaces `file` with `content` (mode 0600). On an error the old content is still there and
// the temporary file is gone.
std::error_code replace_file(const std::filesystem::path& file, std::string_view content);

// Writes all of `bytes` to `fd`, again after a short write or EINTR.
std::error_code write_all(int fd, std::string_view bytes);

}  // namespace drivegate
