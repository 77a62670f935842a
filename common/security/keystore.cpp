#include "common/security/keystore.hpp"

#include <fcntl.h>
#include <openssl/bn.h>
#include <openssl/err.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/pkcs7.h>
#include <openssl/x509.h>
#include <openssl/x509v3.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <memory>

#include "common/security/openssl_handles.hpp"
#include "common/transport/dds_names.hpp"
#include "common/transport/interest.hpp"
#include "common/transport/port_plan.hpp"
#include "common/transport/regular_file.hpp"

namespace qswarm {

namespace fs = std::filesystem;

namespace {

using namespace openssl;  // the layer's own handles (openssl_handles.hpp)

constexpr const char* kMakeOne = " (swarm keys SCENARIO --out DIR writes a keystore)";
// Nothing a keystore holds is larger: a larger file is not one of its files.
constexpr std::uintmax_t kMaxFileBytes = 1u << 20;

[[noreturn]] void fail(const fs::path& file, const std::string& what) {
  ERR_clear_error();
  throw KeystoreError(file.string() + ": " + what);
}

// A private key readable by anyone but its owner is no longer private.
void check_private(const fs::path& file) {
  struct stat s {};
  if (::stat(file.c_str(), &s) == 0 && (s.st_mode & 077) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof mode, "%04o", s.st_mode & 07777);
    fail(file, std::string("a private key readable by others than its owner (mode ") + mode +
                   "): chmod 600 it");
  }
}

Bio memory(const std::string& text) {
  return Bio(BIO_new_mem_buf(text.data(), static_cast<int>(text.size())));
}

// The keystore's root, resolved: every file checked must resolve inside it.
fs::path root_of(const fs::path& dir) {
  std::error_code ec;
  fs::path root = fs::canonical(dir, ec);
  if (ec) fail(dir, "cannot be read as a keystore (" + ec.message() + ")" + kMakeOne);
  if (!fs::is_directory(root, ec) || ec) fail(dir, std::string("not a directory") + kMakeOne);
  return root;
}

// A directory of the keystore anyone but its owner could write into would let them swap its
// files.
void check_directory(const fs::path& dir) {
  struct stat st {};
  if (::stat(dir.c_str(), &st) != 0)
    fail(dir, std::string("cannot be read (") + std::strerror(errno) + ")");
  if (!S_ISDIR(st.st_mode)) fail(dir, "not a directory");
  if ((st.st_mode & 022) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof mode, "%04o", st.st_mode & 07777);
    fail(dir, std::string("writable by others than its owner (mode ") + mode +
                  "): chmod go-w it, or make a new keystore");
  }
}

// A file of the keystore, read whole: it must be a regular file inside the keystore (no link out
// of it, no FIFO, no device), not too large, and a private key readable by its owner alone.
std::string read_file(const fs::path& file, const fs::path& root, bool secret) {
  RegularFile f;
  std::string text = read_regular_file(file, kMaxFileBytes, f);
  if (f.problem == RegularFile::Problem::kMissing) fail(file, std::string("missing") + kMakeOne);
  if (f.problem != RegularFile::Problem::kNone) fail(file, f.why);
  std::error_code ec;
  const fs::path rel = fs::canonical(file, ec).lexically_relative(root);
  if (ec || rel.empty() || *rel.begin() == "..") fail(file, "a link out of the keystore");
  if (secret) check_private(file);
  return text;
}

Cert load_certificate(const fs::path& file, const fs::path& root) {
  const std::string pem = read_file(file, root, false);
  Cert c(PEM_read_bio_X509(memory(pem).get(), nullptr, nullptr, nullptr));
  if (!c) fail(file, std::string("not a PEM certificate") + kMakeOne);
  // X509_cmp_current_time: -1 before now, 1 after, 0 on a malformed time.
  if (X509_cmp_current_time(X509_get0_notBefore(c.get())) >= 0)
    fail(file, "not valid yet (its start date is in the future)");
  if (X509_cmp_current_time(X509_get0_notAfter(c.get())) <= 0)
    fail(file, "expired (swarm keys --days sets how long a keystore lasts)");
  return c;
}

std::string common_name(X509* c) {
  char cn[256] = {};
  const int n = X509_NAME_get_text_by_NID(X509_get_subject_name(c), NID_commonName, cn, sizeof cn);
  return n > 0 ? std::string(cn, static_cast<std::size_t>(n)) : std::string();
}

// The content of an S/MIME file signed by the keystore's authority (`store`).
std::string signed_content(const fs::path& file, const fs::path& root, X509_STORE* store) {
  const std::string smime = read_file(file, root, false);
  BIO* content = nullptr;
  Pkcs7 p7(SMIME_read_PKCS7(memory(smime).get(), &content));
  const Bio detached(content);
  Bio out(BIO_new(BIO_s_mem()));
  if (!p7 || PKCS7_verify(p7.get(), nullptr, store, content, out.get(), 0) != 1)
    fail(file, "not signed by the keystore's authority, or altered since");
  return text_of(out.get());
}

Store store_of(X509* ca) {
  Store s(X509_STORE_new());
  X509_STORE_add_cert(s.get(), ca);
  return s;
}

}  // namespace

namespace {
constexpr const char* kAgentPrefix = "agent-";
}  // namespace

std::string Keystore::agent_identity(AgentId id) { return kAgentPrefix + std::to_string(id); }

std::optional<AgentId> Keystore::agent_of_identity(const std::string& identity) {
  const std::string prefix = kAgentPrefix;
  if (identity.rfind(prefix, 0) != 0) return std::nullopt;
  // The id as agent partitions spell it (digits, no leading zero): the same parser.
  return agent_of_partition("a" + identity.substr(prefix.size()));
}

bool Keystore::compose() const {
  std::error_code ec;
  return fs::is_directory(dir_ / kMember, ec);
}

std::string Keystore::identity_of_agent(AgentId id, bool claiming) const {
  if (compose()) return kMember;
  if (claiming)
    throw KeystoreError(dir_.string() +
                        ": one identity per agent; a replica that claims its id (--id auto) needs "
                        "a compose keystore (swarm keys SCENARIO --out DIR --compose)");
  return agent_identity(id);
}

fs::path Keystore::certificate(const std::string& identity) const {
  return dir_ / identity / "cert.pem";
}
fs::path Keystore::private_key(const std::string& identity) const {
  return dir_ / identity / "key.pem";
}
fs::path Keystore::permissions(const std::string& identity) const {
  return dir_ / identity / "permissions.p7s";
}

void Keystore::check(const std::vector<std::string>& identities) const {
  const fs::path root = root_of(dir_);
  check_directory(dir_);
  std::error_code ec;
  if (fs::exists(dir_ / "private", ec)) {
    // The authority's key: only its mode (no process that flies reads it).
    check_directory(dir_ / "private");
    if (fs::exists(ca_key(), ec)) check_private(ca_key());
  }
  const Cert ca = load_certificate(ca_certificate(), root);
  const Store store = store_of(ca.get());
  signed_content(governance(), root, store.get());
  for (const std::string& identity : identities) {
    if (!fs::exists(dir_ / identity, ec))
      fail(certificate(identity), std::string("missing") + kMakeOne);
    check_directory(dir_ / identity);
    const Cert cert = load_certificate(certificate(identity), root);
    const StoreCtx ctx(X509_STORE_CTX_new());
    if (!ctx || X509_STORE_CTX_init(ctx.get(), store.get(), cert.get(), nullptr) != 1 ||
        X509_verify_cert(ctx.get()) != 1)
      fail(certificate(identity), "not issued by the keystore's authority");
    const std::string named = common_name(cert.get());
    if (named != identity)
      fail(certificate(identity), "the certificate of " + (named.empty() ? "no one" : named) +
                                      ", not of " + identity +
                                      " (identities swapped?): make a new keystore");
    const std::string pem = read_file(private_key(identity), root, true);
    const Key key(PEM_read_bio_PrivateKey(memory(pem).get(), nullptr, nullptr, nullptr));
    if (!key) fail(private_key(identity), "not a private key");
    if (X509_check_private_key(cert.get(), key.get()) != 1)
      fail(private_key(identity), "does not belong to " + certificate(identity).string());
    const std::string grant = signed_content(permissions(identity), root, store.get());
    if (grant.find("<subject_name>CN=" + identity + "</subject_name>") == std::string::npos)
      fail(permissions(identity), "permissions granted to another identity than " + identity);
    // An agent's permissions must bind its id to its own partition: without that, readers would
    // bind its writers to nothing, or (older keystores) any agent's key.
    if (const std::optional<AgentId> id = agent_of_identity(identity)) {
      const std::string mine =
          dds_names::bound_partition(dds_names::one_run_pattern(dds_names::kRunStream), *id);
      if (grant.find("<partition>" + mine + "</partition>") == std::string::npos)
        fail(permissions(identity), "permissions that do not bind " + identity +
                                        " to its own partition (made by an older swarm keys?): "
                                        "make a new keystore");
    }
  }
}

void Keystore::check_run(const std::vector<AgentId>& ids) const {
  root_of(dir_);
  if (compose())
    throw KeystoreError(dir_.string() +
                        ": a compose keystore (one member identity for replicas that claim their "
                        "ids); a secure run needs one identity per agent (swarm keys SCENARIO "
                        "--out DIR)");
  std::vector<std::string> identities;
  identities.reserve(ids.size() + 1);
  for (const AgentId id : ids) identities.push_back(agent_identity(id));
  identities.emplace_back(kSupervisor);
  check(identities);
}

std::vector<std::pair<std::string, std::string>> Keystore::participant_properties(
    const std::string& identity) const {
  const auto uri = [](const fs::path& p) { return "file://" + p.string(); };  // as Fast DDS wants
  return {
      {"dds.sec.auth.plugin", "builtin.PKI-DH"},
      {"dds.sec.auth.builtin.PKI-DH.identity_ca", uri(ca_certificate())},
      {"dds.sec.auth.builtin.PKI-DH.identity_certificate", uri(certificate(identity))},
      {"dds.sec.auth.builtin.PKI-DH.private_key", uri(private_key(identity))},
      {"dds.sec.access.plugin", "builtin.Access-Permissions"},
      {"dds.sec.access.builtin.Access-Permissions.permissions_ca", uri(ca_certificate())},
      {"dds.sec.access.builtin.Access-Permissions.governance", uri(governance())},
      {"dds.sec.access.builtin.Access-Permissions.permissions", uri(permissions(identity))},
      {"dds.sec.crypto.plugin", "builtin.AES-GCM-GMAC"},
  };
}

}  // namespace qswarm
