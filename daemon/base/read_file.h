// Reading a file the configuration names (the configuration itself, TLS certificates and keys,
// a password file) without being trapped by it: opened non-blocking, so a FIFO or a device
// cannot hang the daemon (at start-up, or on the event loop at SIGHUP); accepted only when it is
// a regular file, and no larger than the caller's bound. Every refusal says which and why.
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>

namespace drivegate {

// The whole of `path`, or nothing and `error` ("/etc/x.pem: not a regular file (a FIFO)",
// "...: 3 MiB, more than the 1 MiB allowed").
std::optional<std::string> read_regular_file(const std::filesystem::path& path,
                                             std::size_t max_bytes, std::string& error);

// Whether `path` is a regular file that may be read (checked the same way, its content left
// alone): for files a library reads by path itself (libmosquitto's TLS files).
bool is_readable_regular_file(const std::filesystem::path& path, std::string& error);

}  // namespace drivegate
