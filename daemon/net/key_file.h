// Key files the configuration names (a TLS listener's, the MQTT client's): one rule for every
// northbound that holds a secret.
#pragma once

#include <filesystem>
#include <string>

namespace drivegate::net {

// A private key (or a password file) others may read is as good as published: false and `error`
// (naming the file and the fix) when its mode lets others read it or it cannot be read at all.
bool key_permissions_ok(const std::filesystem::path& key, std::string& error);

}  // namespace drivegate::net
