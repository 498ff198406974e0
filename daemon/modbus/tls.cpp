#include "tls.h"

#include <openssl/asn1.h>
#include <openssl/err.h>
#include <openssl/objects.h>
#include <openssl/pem.h>
#include <openssl/ssl.h>
#include <openssl/x509.h>
#include <openssl/x509v3.h>
#include <sys/stat.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>

#include "base/read_file.h"
#include "net/key_file.h"

namespace drivegate::modbus {
namespace {

namespace ssl = boost::asio::ssl;

// A PEM certificate chain, key or CA bundle is a few KiB; anything near this is not one.
constexpr std::size_t kMaxPemFile = 1024 * 1024;

// The CA names from a PEM bundle in memory, for the CertificateRequest.
STACK_OF(X509_NAME) * client_ca_names(const std::string& pem) {
  const std::unique_ptr<BIO, decltype(&BIO_free)> bio(
      BIO_new_mem_buf(pem.data(), static_cast<int>(pem.size())), &BIO_free);
  STACK_OF(X509_NAME)* names = sk_X509_NAME_new_null();
  if (!bio || names == nullptr) return names;
  while (X509* cert = PEM_read_bio_X509(bio.get(), nullptr, nullptr, nullptr)) {
    if (X509_NAME* name = X509_NAME_dup(X509_get_subject_name(cert))) {
      sk_X509_NAME_push(names, name);
    }
    X509_free(cert);
  }
  ERR_clear_error();  // the end of the bundle reads as an error
  return names;
}

// Names the file and the step in every error.
std::string failure(const std::filesystem::path& file, std::string_view what,
                    const boost::system::error_code& ec) {
  return std::string(what) + " " + file.string() + ": " + ec.message();
}

}  // namespace

std::shared_ptr<ssl::context> make_tls_context(const TlsOptions& o, std::string& error) {
  if (!net::key_permissions_ok(o.key, error)) return nullptr;
  auto ctx = std::make_shared<ssl::context>(ssl::context::tls_server);
  SSL_CTX* native = ctx->native_handle();
  // TLS 1.2 at least (MB-TCP-Security R-01 and later); OpenSSL negotiates 1.3 when both have it.
  SSL_CTX_set_min_proto_version(native, TLS1_2_VERSION);
  ctx->set_options(ssl::context::default_workarounds | ssl::context::no_compression |
                   ssl::context::single_dh_use);
  // Each file read here (regular files only, never a FIFO that would hang the loop at SIGHUP),
  // then handed to OpenSSL from memory.
  std::string why;
  const auto cert = read_regular_file(o.cert, kMaxPemFile, why);
  const auto key = cert ? read_regular_file(o.key, kMaxPemFile, why) : std::nullopt;
  const auto ca = key ? read_regular_file(o.ca, kMaxPemFile, why) : std::nullopt;
  if (!ca) {
    error = "cannot read " + why;
    return nullptr;
  }
  boost::system::error_code ec;
  if (ctx->use_certificate_chain(boost::asio::buffer(*cert), ec); ec) {
    error = failure(o.cert, "cannot load certificate", ec);
    return nullptr;
  }
  if (ctx->use_private_key(boost::asio::buffer(*key), ssl::context::pem, ec); ec) {
    error = failure(o.key, "cannot load key", ec);
    return nullptr;
  }
  if (SSL_CTX_check_private_key(native) != 1) {
    error = "key " + o.key.string() + " does not match certificate " + o.cert.string();
    return nullptr;
  }
  if (ctx->add_certificate_authority(boost::asio::buffer(*ca), ec); ec) {
    error = failure(o.ca, "cannot load CA", ec);
    return nullptr;
  }
  // The CA names go in the CertificateRequest, so a client holding several certificates picks
  // the right one.
  SSL_CTX_set_client_CA_list(native, client_ca_names(*ca));
  // Mutual authentication: a client without a certificate the CA signed is refused in the
  // handshake (MB-TCP-Security R-44).
  ctx->set_verify_mode(ssl::verify_peer | ssl::verify_fail_if_no_peer_cert);
  // Resumed sessions keep their verified peer; OpenSSL refuses resumption with client
  // verification unless the context has an id.
  static constexpr unsigned char kSessionContext[] = "drivegate-modbus";
  SSL_CTX_set_session_id_context(native, kSessionContext, sizeof kSessionContext - 1);
  return ctx;
}

std::optional<std::string> certificate_role(X509* certificate) {
  if (certificate == nullptr) return std::nullopt;
  const std::unique_ptr<ASN1_OBJECT, decltype(&ASN1_OBJECT_free)> oid(OBJ_txt2obj(kRoleOid, 1),
                                                                      &ASN1_OBJECT_free);
  if (!oid) return std::nullopt;
  const int at = X509_get_ext_by_OBJ(certificate, oid.get(), -1);
  if (at < 0) return std::nullopt;
  const ASN1_OCTET_STRING* data = X509_EXTENSION_get_data(X509_get_ext(certificate, at));
  const unsigned char* p = ASN1_STRING_get0_data(data);
  const std::unique_ptr<ASN1_UTF8STRING, decltype(&ASN1_UTF8STRING_free)> role(
      d2i_ASN1_UTF8STRING(nullptr, &p, ASN1_STRING_length(data)), &ASN1_UTF8STRING_free);
  if (!role) return std::nullopt;
  return std::string(reinterpret_cast<const char*>(ASN1_STRING_get0_data(role.get())),
                     static_cast<std::size_t>(ASN1_STRING_length(role.get())));
}

std::string certificate_subject(X509* certificate) {
  if (certificate == nullptr) return "(none)";
  const std::unique_ptr<BIO, decltype(&BIO_free)> bio(BIO_new(BIO_s_mem()), &BIO_free);
  X509_NAME_print_ex(bio.get(), X509_get_subject_name(certificate), 0,
                     XN_FLAG_ONELINE & ~ASN1_STRFLGS_ESC_MSB);
  char* text = nullptr;
  const long n = BIO_get_mem_data(bio.get(), &text);
  return {text, static_cast<std::size_t>(n)};
}

}  // namespace drivegate::modbus
