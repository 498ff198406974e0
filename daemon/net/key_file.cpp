#include "net/key_file.h"

#include <sys/stat.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace drivegate::net {

bool key_permissions_ok(const std::filesystem::path& key, std::string& error) {
  struct stat st {};
  if (::stat(key.c_str(), &st) != 0) {
    error = "cannot read key " + key.string() + ": " + std::strerror(errno);
    return false;
  }
  if ((st.st_mode & S_IRWXO) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof mode, "%04o", static_cast<unsigned>(st.st_mode & 07777));
    error = "key " + key.string() + " is readable by others (mode " + mode +
            "): refused; make it chmod 0600 (or 0640 for a group the service is in)";
    return false;
  }
  return true;
}

}  // namespace drivegate::net
