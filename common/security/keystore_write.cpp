// Keystore::write: `swarm keys`. The governance and permissions are written from the convention
// dds_names spells (topics, the run's partitions, an agent's own partition), so that what the
// adapter publishes into and what a certificate may publish into cannot drift apart.
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
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <memory>

#include "common/security/keystore.hpp"
#include "common/security/openssl_handles.hpp"
#include "common/transport/dds_names.hpp"
#include "common/transport/port_plan.hpp"

namespace qswarm {

namespace fs = std::filesystem;

namespace {

using namespace openssl;  // the layer's own handles (openssl_handles.hpp)

[[noreturn]] void cannot(const fs::path& where, const std::string& what) {
  unsigned long e = ERR_get_error();
  char why[256] = {};
  if (e != 0) ERR_error_string_n(e, why, sizeof why);
  ERR_clear_error();
  throw KeystoreError(where.string() + ": " + what + (e != 0 ? std::string(" (") + why + ")" : ""));
}

// `text` into a new file of this mode (a private key: 0600, whatever the umask).
void write_new(const fs::path& file, const std::string& text, mode_t mode) {
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, mode);
  if (fd < 0) cannot(file, std::string("cannot write (") + std::strerror(errno) + ")");
  const bool ok = ::fchmod(fd, mode) == 0 &&
                  ::write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size());
  const int saved = errno;
  ::close(fd);
  if (!ok) cannot(file, std::string("cannot write (") + std::strerror(saved) + ")");
}

Key new_key(const fs::path& where) {
  Key k(EVP_EC_gen("P-256"));  // prime256v1
  if (!k) cannot(where, "cannot make a key");
  return k;
}

void add_extension(X509* cert, X509* issuer, int nid, const char* value) {
  X509V3_CTX ctx;
  X509V3_set_ctx(&ctx, issuer, cert, nullptr, nullptr, 0);
  const Ext e(X509V3_EXT_conf_nid(nullptr, &ctx, nid, value));
  if (!e || X509_add_ext(cert, e.get(), -1) != 1) cannot("certificate", "cannot add an extension");
}

// A certificate for `key` naming `subject` (CN, and O), signed by `issuer` with `issuer_key`
// (itself when null: the authority's own), valid from now for `days`.
Cert new_certificate(EVP_PKEY* key, const std::string& cn, const char* org, X509* issuer,
                     EVP_PKEY* issuer_key, int days) {
  Cert c(X509_new());
  Bn serial(BN_new());
  if (!c || !serial || BN_rand(serial.get(), 64, BN_RAND_TOP_ANY, BN_RAND_BOTTOM_ANY) != 1 ||
      !BN_to_ASN1_INTEGER(serial.get(), X509_get_serialNumber(c.get())))
    cannot(cn, "cannot make a certificate");
  X509_set_version(c.get(), 2);
  X509_gmtime_adj(X509_getm_notBefore(c.get()), 0);
  X509_gmtime_adj(X509_getm_notAfter(c.get()), 86400L * days);
  X509_set_pubkey(c.get(), key);
  // One name component for an identity: Fast DDS compares a grant's subject with the
  // certificate's in RFC 2253 order, where two would have to be written backwards.
  X509_NAME* name = X509_get_subject_name(c.get());
  X509_NAME_add_entry_by_txt(name, "CN", MBSTRING_UTF8,
                             reinterpret_cast<const unsigned char*>(cn.c_str()), -1, -1, 0);
  if (org)
    X509_NAME_add_entry_by_txt(name, "O", MBSTRING_UTF8,
                               reinterpret_cast<const unsigned char*>(org), -1, -1, 0);
  X509* signer = issuer ? issuer : c.get();
  X509_set_issuer_name(c.get(), X509_get_subject_name(signer));
  add_extension(c.get(), signer, NID_basic_constraints,
                issuer ? "critical,CA:FALSE" : "critical,CA:TRUE");
  add_extension(c.get(), signer, NID_subject_key_identifier, "hash");
  add_extension(c.get(), signer, NID_authority_key_identifier, "keyid:always");
  if (X509_sign(c.get(), issuer_key ? issuer_key : key, EVP_sha256()) == 0)
    cannot(cn, "cannot sign a certificate");
  return c;
}

std::string pem_of(X509* c) {
  Bio b(BIO_new(BIO_s_mem()));
  PEM_write_bio_X509(b.get(), c);
  return text_of(b.get());
}

std::string pem_of(EVP_PKEY* k) {
  Bio b(BIO_new(BIO_s_mem()));
  PEM_write_bio_PrivateKey(b.get(), k, nullptr, nullptr, 0, nullptr, nullptr);
  return text_of(b.get());
}

// `xml` signed by the authority as S/MIME, clear text and detached (openssl smime -sign -text).
std::string signed_by(X509* ca, EVP_PKEY* ca_key, const std::string& xml, const fs::path& where) {
  const int flags = PKCS7_DETACHED | PKCS7_STREAM | PKCS7_TEXT;
  Bio in(BIO_new_mem_buf(xml.data(), static_cast<int>(xml.size())));
  Pkcs7 p7(PKCS7_sign(ca, ca_key, nullptr, in.get(), flags));
  Bio out(BIO_new(BIO_s_mem()));
  if (!p7 || SMIME_write_PKCS7(out.get(), p7.get(), in.get(), flags) != 1)
    cannot(where, "cannot sign");
  return text_of(out.get());
}

std::string domains() {
  return "<domains><id_range><min>0</min><max>" + std::to_string(PortPlan::kMaxDomain) +
         "</max></id_range></domains>";
}

std::string governance_xml() {
  return R"(<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-Security/20170801/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      )" +
         domains() +
         R"(
      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
      <enable_join_access_control>true</enable_join_access_control>
      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
      <rtps_protection_kind>ENCRYPT</rtps_protection_kind>
      <topic_access_rules>
        <topic_rule>
          <topic_expression>*</topic_expression>
          <enable_discovery_protection>true</enable_discovery_protection>
          <enable_liveliness_protection>true</enable_liveliness_protection>
          <enable_read_access_control>true</enable_read_access_control>
          <enable_write_access_control>true</enable_write_access_control>
          <metadata_protection_kind>ENCRYPT</metadata_protection_kind>
          <data_protection_kind>ENCRYPT</data_protection_kind>
        </topic_rule>
      </topic_access_rules>
    </domain_rule>
  </domain_access_rules>
</dds>
)";
}

std::string rule(const char* kind, const std::vector<std::string>& topics,
                 const std::vector<std::string>& partitions) {
  std::string r = std::string("        <") + kind + "><topics>";
  for (const std::string& t : topics) r += "<topic>" + t + "</topic>";
  r += "</topics><partitions>";
  for (const std::string& p : partitions) r += "<partition>" + p + "</partition>";
  return r + "</partitions></" + kind + ">\n";
}

// Fast DDS checks a writer against the first allow_rule naming its topic, with the partitions of
// every <publish> in that rule: one rule per topic keeps each topic's partitions its own.
std::string allow_rule(const std::string& rules) {
  return "      <allow_rule>\n        " + domains() + "\n" + rules + "      </allow_rule>\n";
}

std::string grants(const std::string& identity) {
  using namespace dds_names;
  const std::string run = one_run_pattern(kRunStream), record = one_run_pattern(kRecordStream);
  const std::string any_run = any_run_partition(kRunStream),
                    any_record = any_run_partition(kRecordStream);
  if (identity == Keystore::kSupervisor)
    return allow_rule(rule("subscribe", {kRecordTopic}, {any_record}));
  if (identity == Keystore::kMember)  // any agent: replicas learn their id only as they claim it
    return allow_rule(rule("publish", {kStateTopic, kClaimTopic}, {any_run}) +
                      rule("publish", {kRecordTopic}, {any_record}) +
                      rule("subscribe", {kStateTopic, kClaimTopic}, {any_run}));
  // agent-ID: state only into the run's partition, its own, and partitions that name no agent
  // (agent partitions start with 'a'); records only into the record partition and its own.
  const AgentId id = Keystore::agent_of_identity(identity).value_or(0);
  return allow_rule(
             rule("publish", {kStateTopic}, {run, bound_partition(run, id), run + "/[!a]*"}) +
             rule("subscribe", {kStateTopic, kClaimTopic}, {any_run})) +
         allow_rule(rule("publish", {kRecordTopic}, {record, bound_partition(record, id)})) +
         allow_rule(rule("publish", {kClaimTopic}, {run}));
}

std::string stamp(std::time_t t) {
  char buf[32];
  std::tm tm{};
  gmtime_r(&t, &tm);
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%S", &tm);
  return buf;
}

std::string permissions_xml(const std::string& identity, int days) {
  // Fast DDS reads the permissions' times as local time: a day's margin for any time zone.
  const std::time_t now = std::time(nullptr);
  return R"(<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-Security/20170801/omg_shared_ca_permissions.xsd">
  <permissions>
    <grant name=")" +
         identity + R"(">
      <subject_name>CN=)" +
         identity + R"(</subject_name>
      <validity>
        <not_before>)" +
         stamp(now - 86400) + R"(</not_before>
        <not_after>)" +
         stamp(now + 86400L * days) + R"(</not_after>
      </validity>
)" + grants(identity) +
         R"(      <default>DENY</default>
    </grant>
  </permissions>
</dds>
)";
}

}  // namespace

Keystore Keystore::write(const fs::path& out, const std::vector<AgentId>& ids, int days,
                         bool compose) {
  std::error_code ec;
  const fs::file_type type = fs::symlink_status(out, ec).type();
  if (type != fs::file_type::not_found) {
    if (ec || type != fs::file_type::directory || !fs::is_empty(out, ec) || ec)
      throw KeystoreError(out.string() +
                          ": exists and is not an empty directory (a keystore is never "
                          "overwritten)");
  }
  // "keys/" and "keys" are one directory: its parent is where the keystore is made.
  fs::path whole = fs::absolute(out, ec).lexically_normal();
  if (!whole.has_filename()) whole = whole.parent_path();
  const fs::path parent = whole.parent_path();
  fs::create_directories(parent, ec);
  if (ec) throw KeystoreError(parent.string() + ": cannot create (" + ec.message() + ")");
  std::string work_name = (parent / ".keys-XXXXXX").string();
  if (!::mkdtemp(work_name.data()))
    throw KeystoreError(parent.string() + ": cannot write (" + std::strerror(errno) + ")");
  const fs::path work = work_name;
  try {
    ::chmod(work.c_str(), 0700);  // as every identity's: only its owner lists it
    const auto dir = [&](const fs::path& d, mode_t mode) {
      if (::mkdir(d.c_str(), mode) != 0 || ::chmod(d.c_str(), mode) != 0)
        cannot(d, std::string("cannot create (") + std::strerror(errno) + ")");
    };
    dir(work / "private", 0700);
    const Key ca_key = new_key(work);
    const Cert ca =
        new_certificate(ca_key.get(), "qswarm keystore CA", "qswarm", nullptr, nullptr, days);
    write_new(work / "private" / "ca.key.pem", pem_of(ca_key.get()), 0600);
    write_new(work / "ca.cert.pem", pem_of(ca.get()), 0644);
    const std::string gov = governance_xml();
    write_new(work / "governance.xml", gov, 0644);
    write_new(work / "governance.p7s", signed_by(ca.get(), ca_key.get(), gov, work), 0644);
    std::vector<std::string> identities;
    if (compose) {
      identities.emplace_back(kMember);
    } else {
      for (const AgentId id : ids) identities.push_back(agent_identity(id));
    }
    identities.emplace_back(kSupervisor);
    for (const std::string& identity : identities) {
      const fs::path d = work / identity;
      dir(d, 0700);
      const Key key = new_key(d);
      const Cert cert = new_certificate(key.get(), identity, nullptr, ca.get(), ca_key.get(), days);
      write_new(d / "key.pem", pem_of(key.get()), 0600);
      write_new(d / "cert.pem", pem_of(cert.get()), 0644);
      const std::string perm = permissions_xml(identity, days);
      write_new(d / "permissions.xml", perm, 0644);
      write_new(d / "permissions.p7s", signed_by(ca.get(), ca_key.get(), perm, d), 0644);
    }
    if (type == fs::file_type::directory) fs::remove(whole, ec);  // empty, checked above
    fs::rename(work, whole, ec);
    if (ec) throw KeystoreError(out.string() + ": cannot write (" + ec.message() + ")");
  } catch (...) {
    fs::remove_all(work, ec);
    throw;
  }
  return Keystore(out);
}

}  // namespace qswarm
