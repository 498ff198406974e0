// Small facts the daemon keeps across restarts (the Sparkplug bdSeq, docs/mqtt.md), each in its
// own file under the state directory (systemd's StateDirectory=, /var/lib/drivegate). A file is
// replaced whole or not at all: the new content goes to a temporary file beside it, which is
// synced and then renamed over the old one, and the directory synced after the rename, so a power
// cut leaves either the old content or the new, never a mix or an empty file.
//
// Nothing found in the state directory is taken to be what its name says (docs/security.md):
// whatever has the temporary file's name (a FIFO, which would block the open; a link, hard or
// symbolic, which would be written through) is removed first and the temporary made anew
// (O_EXCL), never opened; the rename replaces the name, not what a link there points to. Files
// are read with base/read_file.h (non-blocking, links refused, regular files only), and one that
// cannot be used is set aside under another name, kept for a human to look at.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>

namespace drivegate {

// Replaces `file` with `content` (mode 0600). On an error the old content is still there and
// the temporary file is gone.
std::error_code replace_file(const std::filesystem::path& file, std::string_view content);
// The same for `name` in the directory open as `dir_fd`.
std::error_code replace_file_at(int dir_fd, const std::string& name, std::string_view content);

// Writes all of `bytes` to `fd`, again after a short write or EINTR.
std::error_code write_all(int fd, std::string_view bytes);

// Moves what has `name` (in the directory open as `dir_fd`, or AT_FDCWD) out of the way, without
// opening or following it, to the first free one of "<name>.bad", "<name>.bad-2" ...
// "<name>.bad-9": that new name, or nothing and `error` (nothing of that name, all of those taken,
// or the rename failed).
std::optional<std::string> set_aside(int dir_fd, const std::string& name, std::string& error);

}  // namespace drivegate
