#pragma once

#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "common/core/agent.hpp"

namespace qswarm {

// What is wrong with a keystore: the message names the file and what was expected ("DIR/agent-2/
// cert.pem: ..."). A person's input: the process exits 2 before anything flies.
class KeystoreError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A DDS-Security keystore, as RunDir is a run directory: the one place that names its files, owns
// the identity and partition convention, writes one (`swarm keys`) and checks one (`swarm run
// --secure`, and every agent and supervisor before it makes its participant). The layout follows
// ROS 2's sros2: one authority (EC prime256v1, SHA-256) signs every identity and, as S/MIME, the
// governance and every permissions file.
//
//   ca.cert.pem                   the authority (identity CA and permissions CA)
//   private/ca.key.pem            its key: keep it off the machines that fly
//   governance.xml, .p7s          authentication required, everything encrypted, no stranger
//   IDENTITY/cert.pem, key.pem    an identity: agent-ID per agent and supervisor; or, for compose
//   IDENTITY/permissions.xml,.p7s replicas that claim their ids, one member every replica shares
//
// An agent's writers publish into a partition of its own id under the run's (dds_names::
// bound_partition: ".../a3"), and agent-ID's permissions let it publish state and records only
// there among agent partitions: readers take a sample keyed ID only from a writer bound to ID
// (WriterRegistry), so the holder of agent 3's key cannot publish as agent 5.
class Keystore {
 public:
  explicit Keystore(std::filesystem::path dir) : dir_(std::move(dir)) {}
  const std::filesystem::path& path() const { return dir_; }

  static constexpr const char* kSupervisor = "supervisor";
  static constexpr const char* kMember = "member";
  static std::string agent_identity(AgentId id);  // "agent-3"
  // The agent an identity is ("agent-3" -> 3); nothing for the supervisor or the member.
  static std::optional<AgentId> agent_of_identity(const std::string& identity);
  // Whether it holds the member identity (swarm keys --compose).
  bool compose() const;
  // Who agent `id` speaks as here: its own identity, or the member in a compose keystore. A
  // replica that claims its id (`claiming`) cannot hold a certificate for it in advance: it needs
  // a compose keystore (KeystoreError otherwise).
  std::string identity_of_agent(AgentId id, bool claiming = false) const;

  std::filesystem::path ca_certificate() const { return dir_ / "ca.cert.pem"; }
  std::filesystem::path ca_key() const { return dir_ / "private" / "ca.key.pem"; }
  std::filesystem::path governance() const { return dir_ / "governance.p7s"; }
  std::filesystem::path certificate(const std::string& identity) const;
  std::filesystem::path private_key(const std::string& identity) const;
  std::filesystem::path permissions(const std::string& identity) const;

  // Checks what the processes speaking as these identities need, before any of them flies:
  // every file there and regular, none a link out of the keystore; no private key readable and no
  // directory writable by anyone but its owner; the authority's certificate valid now; the
  // governance and each identity's permissions signed by it; each certificate issued by it, valid
  // now and naming the identity whose directory it sits in, its key its own; each grant naming that
  // identity, and an agent's binding it to its own partition. Throws KeystoreError naming the
  // first file that is wrong. Writes nothing.
  void check(const std::vector<std::string>& identities) const;
  // What a secure run of these agents needs (`swarm run --secure`): each agent's identity and the
  // supervisor's; a compose keystore is refused (its member may speak as any agent).
  void check_run(const std::vector<AgentId>& ids) const;

  // Writes a new keystore at `out` for these agents and the supervisor (or, `compose`, the member
  // and the supervisor), valid for `days`: made beside it and renamed into place, so that a
  // keystore is never half-written; `out` must not exist or be empty. Throws KeystoreError.
  static Keystore write(const std::filesystem::path& out, const std::vector<AgentId>& ids, int days,
                        bool compose);

  // The participant properties DDS-Security's built-in plugins take for `identity` here.
  std::vector<std::pair<std::string, std::string>> participant_properties(
      const std::string& identity) const;

 private:
  std::filesystem::path dir_;
};

}  // namespace qswarm
