// Reading a file the configuration names (the configuration itself, TLS certificates and keys,
// a password file) or one the daemon keeps (base/state_file.h) without being trapped by it:
// opened non-blocking, so a FIFO or a device cannot hang the daemon (at start-up, or on the event
// loop at SIGHUP); accepted only when it is a regular file, and no larger than the caller's bound.
// Every refusal says which and why.
#pragma once

#include <sys/types.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

namespace drivegate {

// Whether a symbolic link at the name is followed (a file the configuration names: an
// administrator's link is theirs) or refused as one (a file in the state directory, where a link
// would redirect what the daemon reads or writes).
enum class Links : std::uint8_t { follow, refuse };

// The whole of `path`, or nothing and `error` ("/etc/x.pem: not a regular file (a FIFO)",
// "...: 3 MiB, more than the 1 MiB allowed").
std::optional<std::string> read_regular_file(const std::filesystem::path& path,
                                             std::size_t max_bytes, std::string& error,
                                             Links links = Links::follow);

// Whether `path` is a regular file that may be read (checked the same way, its content left
// alone): for files a library reads by path itself (libmosquitto's TLS files).
bool is_readable_regular_file(const std::filesystem::path& path, std::string& error);

// Opens `name` (in the directory open as `dir_fd`, or AT_FDCWD) with `flags` (O_RDONLY or
// O_RDWR, no O_CREAT) without blocking, and keeps it only when it is a regular file: its
// descriptor (O_NONBLOCK is left set: it changes nothing for a regular file), or -1 and `error`
// naming it and what it is. errno is ENOENT after -1 when nothing has that name.
int open_regular_file(int dir_fd, const std::string& name, int flags, Links links,
                      std::string& error);

// What a file of type `mode` (st_mode) is, for a message: "a FIFO", "a directory", "a symbolic
// link"...
const char* file_kind(mode_t mode);

}  // namespace drivegate
