// Modbus/TCP Security (MB-TCP-Security v21, 2018): the TLS side of a listener. The server's
// context (its certificate and key, the CA its clients' certificates must chain to, TLS 1.2 at
// least, a client certificate required) and the role a client certificate carries. The MBAP ADU
// travels inside TLS unchanged, so framing and dispatch are the same as on plain TCP.
#pragma once

#include <boost/asio/ssl/context.hpp>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include "backend.h"

using X509 = struct x509_st;

namespace drivegate::modbus {

// Role names (as carried in client certificates) to access levels.
using RoleMap = std::map<std::string, AccessLevel, std::less<>>;

struct TlsOptions {
  std::filesystem::path cert;  // PEM: the server's certificate (chain)
  std::filesystem::path key;   // PEM: its private key; refused if others may read it
  std::filesystem::path ca;    // PEM: the CA(s) a client certificate must be signed by
  RoleMap roles;               // a role not in here, or no role, gets the listener's access
  friend bool operator==(const TlsOptions&, const TlsOptions&) = default;
};

// The role extension's OID (MB-TCP-Security, "Role-based client authorization"): the role is an
// ASN.1 UTF8String in the client certificate's X.509v3 extension with this object identifier.
inline constexpr const char* kRoleOid = "1.3.6.1.4.1.50316.802.1";

// Reads the files and builds the context a listener handshakes with: TLS 1.2 minimum (1.3 is
// preferred by OpenSSL when both sides have it), peer verification on, a client without a
// certificate refused. nullptr and `error` (naming the file and what is wrong) when a file is
// missing, unreadable, not PEM, a key others can read, or a key that does not match the
// certificate.
std::shared_ptr<boost::asio::ssl::context> make_tls_context(const TlsOptions& options,
                                                            std::string& error);

// The role in a client certificate, if it has the extension and it is a UTF8String.
std::optional<std::string> certificate_role(X509* certificate);
// The certificate's subject, one line ("CN=plc-1,O=plant"), for the log.
std::string certificate_subject(X509* certificate);

}  // namespace drivegate::modbus
