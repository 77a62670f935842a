// `swarm deploy k8s SCENARIO [--agents N] --out DIR`: the swarm as Kubernetes manifests
// (DIR/quadswarm.yaml), and the same containers as one Pod per process for `podman kube play`
// (DIR/podman.yaml), which runs no StatefulSet, Service or Job. The size is typed once, here.
//
// Agents: a StatefulSet (pod quadswarm-agent-K flies the scenario's K-th agent) behind a headless
// Service. Discovery: two Discovery Servers, each a Deployment behind a ClusterIP Service of its
// own, listed by every process in one order (a client must know each server's GUID prefix, so
// replicas behind one Service cannot work in Fast DDS 2.9; docs/hosts.md). Supervisor: a Job whose
// exit code is the run's, recording onto a PersistentVolumeClaim.
//
// Secure (--keystore): no Discovery Server (Fast DDS 2.9 has none secure); every process finds the
// others by unicast at the addresses of the headless Service, which names the agents and the
// supervisor. The keystore's shared files are one Secret, each identity's certificate, key and
// permissions another, and a pod mounts only its own: a StatefulSet's pods share one template, so
// each agent is a StatefulSet of one. An init container copies the files into the pod's memory
// (an emptyDir) as the keystore check wants them: regular files, the key readable by its owner
// only.
#include <CLI/CLI.hpp>

#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "common/record/json_writer.hpp"
#include "common/scenario/scenario.hpp"
#include "common/security/keystore.hpp"
#include "common/transport/regular_file.hpp"
#include "common/view/foxglove_protocol.hpp"
#include "launcher/commands.hpp"

namespace qswarm {
namespace {

constexpr int kServers = 2;
constexpr int kServerPort = 11811;
constexpr const char* kUid = "10001";  // the image's user (docker/Dockerfile)

// A YAML double-quoted scalar: a JSON string is one (YAML 1.2 reads JSON's escapes), so the
// project's JSON writer escapes quotes, backslashes and control characters alike.
std::string quoted(const std::string& s) {
  std::string out;
  JsonWriter(out).str(s);
  return out;
}

std::string indented(const std::string& text, int spaces) {
  std::string out, pad(static_cast<std::size_t>(spaces), ' ');
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out += (line.empty() ? "" : pad + line) + "\n";
  return out;
}

constexpr const char* kKeysDir = "/keys/store";  // where a pod's keystore is copied to

// A keystore file, as a pod needs it: its name (in its identity's directory, or at the
// keystore's top for the shared ones) and its bytes.
struct KeyFile {
  std::string name, bytes;
};

struct Deploy {
  std::string name = "quadswarm", image, scenario_text;
  int agents = 0;
  std::vector<AgentId> ids;
  bool random_agents = false;
  std::uint32_t domain = 0;
  // Secure: the shared files (under "") and each identity's, by identity.
  std::map<std::string, std::vector<KeyFile>> keys;
  bool secure() const { return !keys.empty(); }
  // podman.yaml: podman kube play runs no Service, so the peers are the pods' names; and podman
  // 4.3 cannot mount a Secret (it panics), so the same files travel as ConfigMaps there.
  bool podman_pods = false;

  std::string server_name(int i) const { return name + "-discovery-" + std::to_string(i); }
  std::string servers() const {
    std::string list;
    for (int i = 0; i < kServers; ++i)
      list += (i ? "," : "") + server_name(i) + ":" + std::to_string(kServerPort);
    return list;
  }
  std::string agent_pod(int k) const { return name + "-agent-" + std::to_string(k); }
  std::string key_object(const std::string& identity) const {
    return name + (identity.empty() ? "-trust" : "-key-" + identity);
  }
  // How a process finds the others: through the servers, or (secure) by unicast at the addresses
  // of the headless Service (on podman, of every pod's name).
  std::string discovery_flags() const {
    if (!secure()) return "";
    std::string peers = name + "-agents";
    if (podman_pods) {
      peers = name + "-supervisor";
      for (int k = 0; k < agents; ++k) peers += "," + agent_pod(k);
    }
    return std::string(" --keystore ") + kKeysDir + " --peer-hosts " + peers;
  }
  // One container, as every manifest runs it: `command` is a shell line (the agents read their
  // ordinal from the pod's name).
  std::string container(const std::string& role, const std::string& command, int indent,
                        bool runs_volume) const {
    std::ostringstream c;
    c << "- name: " << role << "\n"
      << "  image: " << quoted(image) << "\n"
      << "  imagePullPolicy: IfNotPresent\n"
      << "  command: [\"/bin/sh\", \"-c\", " << quoted(command) << "]\n";
    if (!secure() || random_agents) c << "  env:\n";
    if (!secure())
      c << "  - name: QSWARM_DISCOVERY_SERVER\n    value: " << quoted(servers()) << "\n";
    if (random_agents)
      c << "  - name: QSWARM_AGENTS\n    value: " << quoted(std::to_string(agents)) << "\n";
    c << "  volumeMounts:\n"
      << "  - name: scenario\n    mountPath: /etc/quadswarm\n    readOnly: true\n";
    if (runs_volume) c << "  - name: runs\n    mountPath: /runs\n";
    if (secure() && role != "discovery") c << "  - name: keys\n    mountPath: /keys\n";
    return indented(c.str(), indent);
  }
  // Secure: the container that copies `identity`'s files and the shared ones into the pod's
  // keystore before the process starts.
  std::string key_copier(const std::string& identity, int indent) const {
    std::string copy = std::string("umask 077 && mkdir -p ") + kKeysDir + "/" + identity;
    for (const auto& [who, files] : keys) {
      if (!who.empty() && who != identity) continue;
      for (const KeyFile& f : files)
        copy += " && cp -L /etc/quadswarm-" + std::string(who.empty() ? "trust/" : "key/") +
                f.name + " " + kKeysDir + "/" + (who.empty() ? "" : who + "/") + f.name;
    }
    std::ostringstream c;
    c << "initContainers:\n- name: keys\n  image: " << quoted(image)
      << "\n  imagePullPolicy: IfNotPresent\n  command: [\"/bin/sh\", \"-c\", " << quoted(copy)
      << "]\n  volumeMounts:\n"
      << "  - name: trust\n    mountPath: /etc/quadswarm-trust\n    readOnly: true\n"
      << "  - name: key\n    mountPath: /etc/quadswarm-key\n    readOnly: true\n"
      << "  - name: keys\n    mountPath: /keys\n";
    return indented(c.str(), indent);
  }
  std::string key_volume(const std::string& volume, const std::string& object) const {
    // Readable by the pod's group (fsGroup) only, for the init container to copy.
    return "- name: " + volume +
           (podman_pods ? "\n  configMap:\n    name: " : "\n  secret:\n    secretName: ") + object +
           "\n    defaultMode: 0440\n";
  }
  std::string volumes(int indent, bool runs_volume, const std::string& identity = "") const {
    std::ostringstream v;
    v << "volumes:\n"
      << "- name: scenario\n  configMap:\n    name: " << name << "-scenario\n";
    if (runs_volume)
      v << "- name: runs\n  persistentVolumeClaim:\n    claimName: " << name << "-runs\n";
    if (!identity.empty())
      v << key_volume("trust", key_object("")) << key_volume("key", key_object(identity))
        << "- name: keys\n  emptyDir:\n    medium: Memory\n";
    return indented(v.str(), indent);
  }
  // The Secrets (on podman, ConfigMaps) of the keystore: the shared files, then one per identity.
  std::string key_objects() const {
    std::ostringstream y;
    for (const auto& [who, files] : keys) {
      y << "---\napiVersion: v1\nkind: " << (podman_pods ? "ConfigMap" : "Secret")
        << "\nmetadata:\n  name: " << key_object(who) << "\n"
        << (podman_pods ? "" : "type: Opaque\n") << "data:\n";
      for (const KeyFile& f : files)
        y << "  " << f.name << ": " << (podman_pods ? quoted(f.bytes) : base64_encode(f.bytes))
          << "\n";
    }
    return y.str();
  }
  std::string agent_command(int k) const {
    if (secure())
      return "exec swarm-agent --scenario /etc/quadswarm/scenario.txtpb --interface any --id " +
             std::to_string(ids[static_cast<std::size_t>(k)]) +
             " --wait-supervisor --start-timeout 600" + discovery_flags();
    std::string list;
    for (const AgentId id : ids) list += (list.empty() ? "" : " ") + std::to_string(id);
    // Pod NAME-K flies the K-th agent of the scenario (a StatefulSet's ordinal; podman's pods are
    // named alike).
    return "set -- " + list +
           "; shift \"${HOSTNAME##*-}\" && exec swarm-agent --scenario "
           "/etc/quadswarm/scenario.txtpb --interface any --id \"$1\" --wait-supervisor "
           "--start-timeout 600";
  }
  std::string server_command(int i) const {
    return "exec swarm-discovery --servers " + servers() + " --index " + std::to_string(i) +
           " --domain " + std::to_string(domain);
  }
  std::string supervisor_command() const {
    return "exec swarm-supervisor --scenario /etc/quadswarm/scenario.txtpb --interface any "
           "--new-run-in /runs --start-timeout 300" +
           discovery_flags();
  }
  std::string pod_security(int indent) const {
    return indented(std::string("securityContext:\n  runAsUser: ") + kUid +
                        "\n  runAsGroup: " + kUid + "\n  fsGroup: " + kUid + "\n",
                    indent);
  }
  std::string config_map() const {
    return "apiVersion: v1\nkind: ConfigMap\nmetadata:\n  name: " + name +
           // Its indentation said (2 past the key's): a scenario whose first line is indented
           // would otherwise set it.
           "-scenario\ndata:\n  scenario.txtpb: |2\n" + indented(scenario_text, 4);
  }
  std::string claim() const {
    return "apiVersion: v1\nkind: PersistentVolumeClaim\nmetadata:\n  name: " + name +
           "-runs\nspec:\n  accessModes: [\"ReadWriteOnce\"]\n  resources:\n    requests:\n"
           "      storage: 1Gi\n";
  }
  // `extra`: more labels, one "key: value\n" each.
  std::string labels(const std::string& component, int indent,
                     const std::string& extra = "") const {
    return indented(
        "labels:\n  app: " + name + "\n  component: " + component + "\n" + indented(extra, 2),
        indent);
  }
  // What a process's pod spec holds after its security context: the key copier (secure), the
  // container, the volumes.
  std::string pod_spec(const std::string& identity, const std::string& role,
                       const std::string& command, bool runs_volume, int indent) const {
    const std::string own = secure() && role != "discovery" ? identity : "";
    return (own.empty() ? "" : key_copier(own, indent)) + indented("containers:\n", indent) +
           container(role, command, indent, runs_volume) + volumes(indent, runs_volume, own);
  }
  // Secure: the agents and the supervisor, whom the headless Service names for discovery.
  std::string peer_label() const { return secure() ? "peer: dds\n" : ""; }

  std::string kubernetes() const {
    std::ostringstream y;
    y << "# " << name << ": " << agents << (secure() ? " agents, secure" : " agents")
      << " (swarm deploy k8s). kubectl apply -f this file;\n"
      << "# the Job " << name << "-supervisor ends with the run's verdict, its record on the claim "
      << name << "-runs.\n";
    y << config_map() << "---\n" << claim() << key_objects();
    for (int i = 0; i < (secure() ? 0 : kServers); ++i) {
      const std::string s = server_name(i);
      y << "---\napiVersion: v1\nkind: Service\nmetadata:\n  name: " << s << "\nspec:\n"
        << "  selector:\n    app: " << name << "\n    component: " << s << "\n"
        << "  ports:\n  - name: discovery\n    protocol: UDP\n    port: " << kServerPort << "\n";
      y << "---\napiVersion: apps/v1\nkind: Deployment\nmetadata:\n  name: " << s << "\nspec:\n"
        << "  replicas: 1\n  selector:\n    matchLabels:\n      app: " << name
        << "\n      component: " << s << "\n  template:\n    metadata:\n"
        << labels(s, 6) << "    spec:\n"
        << pod_security(6) << pod_spec("", "discovery", server_command(i), false, 6);
    }
    y << "---\napiVersion: v1\nkind: Service\nmetadata:\n  name: " << name << "-agents\nspec:\n"
      << "  clusterIP: None\n  publishNotReadyAddresses: true\n"
      << "  selector:\n    app: " << name << "\n"
      << (secure() ? "    peer: dds\n" : "    component: agent\n");
    // Plain: one StatefulSet, the ordinal the agent. Secure: one per agent, each pod holding its
    // own key.
    for (int k = 0; k < (secure() ? agents : 1); ++k) {
      const std::string set = secure() ? agent_pod(k) : name + "-agent";
      const std::string ordinal = secure() ? "ordinal: \"" + std::to_string(k) + "\"\n" : "";
      y << "---\napiVersion: apps/v1\nkind: StatefulSet\nmetadata:\n  name: " << set
        << "\nspec:\n  serviceName: " << name << "-agents\n  replicas: " << (secure() ? 1 : agents)
        << "\n  podManagementPolicy: Parallel\n  selector:\n    matchLabels:\n      app: " << name
        << "\n      component: agent\n"
        << indented(ordinal, 6) << "  template:\n    metadata:\n"
        << labels("agent", 6, ordinal + peer_label()) << "    spec:\n"
        << pod_security(6) << pod_spec(identity_of(k), "agent", agent_command(k), false, 6);
    }
    y << "---\napiVersion: batch/v1\nkind: Job\nmetadata:\n  name: " << name
      << "-supervisor\nspec:\n  backoffLimit: 0\n  template:\n    metadata:\n"
      << labels("supervisor", 6, peer_label()) << "    spec:\n      restartPolicy: Never\n"
      << pod_security(6)
      << pod_spec(Keystore::kSupervisor, "supervisor", supervisor_command(), true, 6);
    return y.str();
  }
  std::string identity_of(int k) const {
    return Keystore::agent_identity(ids[static_cast<std::size_t>(k)]);
  }

  std::string pod(const std::string& pod_name, const std::string& component,
                  const std::string& role, const std::string& command, bool runs_volume,
                  const std::string& identity = "") const {
    return "---\napiVersion: v1\nkind: Pod\nmetadata:\n  name: " + pod_name + "\n" +
           labels(component, 2) + "spec:\n  restartPolicy: Never\n" + pod_security(2) +
           pod_spec(identity, role, command, runs_volume, 2);
  }
  std::string podman() const {
    Deploy p = *this;
    p.podman_pods = true;
    std::ostringstream y;
    y << "# " << name << ": the containers of quadswarm.yaml as one Pod per process, for\n"
      << "# podman kube play (it runs no StatefulSet, Service or Job"
      << (secure() ? "; the keystore's Secrets are\n# ConfigMaps: podman 4.3 cannot mount a Secret"
                   : "")
      << ").\n";
    y << p.config_map() << "---\n" << p.claim() << p.key_objects();
    for (int i = 0; i < (secure() ? 0 : kServers); ++i)
      y << p.pod(server_name(i), server_name(i), "discovery", server_command(i), false);
    y << p.pod(name + "-supervisor", "supervisor", "supervisor", p.supervisor_command(), true,
               Keystore::kSupervisor);
    for (int k = 0; k < agents; ++k)
      y << p.pod(agent_pod(k), "agent", "agent", p.agent_command(k), false, identity_of(k));
    return y.str();
  }
};

// The files every pod of a secure swarm needs, checked as the processes will check them (one
// identity per agent and the supervisor's; not a compose keystore, whose member key speaks for
// any agent). False, having said why, when the keystore will not do.
bool read_keystore(const std::string& dir, Deploy& d) {
  const Keystore ks(dir);
  std::vector<std::string> identities = {Keystore::kSupervisor};
  for (const AgentId id : d.ids) identities.push_back(Keystore::agent_identity(id));
  try {
    ks.check_run(d.ids);
  } catch (const KeystoreError& e) {
    std::cerr << "swarm deploy k8s: --keystore: " << e.what() << "\n";
    return false;
  }
  const auto add = [&](const std::string& who, const std::filesystem::path& file) {
    RegularFile f;
    std::string bytes = read_regular_file(file.string(), 1 << 20, f);
    if (f.problem != RegularFile::Problem::kNone) {
      std::cerr << "swarm deploy k8s: --keystore: " << f.why << "\n";
      return false;
    }
    d.keys[who].push_back({file.filename().string(), std::move(bytes)});
    return true;
  };
  if (!add("", ks.ca_certificate()) || !add("", ks.governance())) return false;
  for (const std::string& who : identities)
    if (!add(who, ks.certificate(who)) || !add(who, ks.private_key(who)) ||
        !add(who, ks.permissions(who)))
      return false;
  return true;
}

}  // namespace

Command add_deploy_command(CLI::App& app) {
  struct Options {
    std::string scenario, out, image = "localhost/qswarm:latest", name = "quadswarm", keystore;
    int agents = -1;
  };
  auto o = std::make_shared<Options>();
  CLI::App* deploy = app.add_subcommand("deploy", "the swarm as manifests for a cluster");
  CLI::App* k8s = deploy->add_subcommand(
      "k8s", "Kubernetes manifests (quadswarm.yaml) and the same pods for podman kube play");
  deploy->require_subcommand(1);
  k8s->add_option("scenario", o->scenario, "scenario file")->required();
  k8s->add_option("--agents", o->agents,
                  "fly N seeded random agents instead of the scenario's list (the swarm's size, "
                  "typed once: replicas and every process follow it)")
      ->check(CLI::Range(1, static_cast<int>(kMaxSwarmAgents)));
  k8s->add_option("--out", o->out, "directory to write the manifests into (created)")->required();
  k8s->add_option("--image", o->image, "the swarm's image (docker/Dockerfile)");
  k8s->add_option("--keystore", o->keystore,
                  "a secure swarm: the keystore (`swarm keys SCENARIO --out DIR`) as Secrets, each "
                  "pod holding only its own identity (default: the scenario's transport.keystore)");
  k8s->add_option("--name", o->name, "prefix of every object's name (default quadswarm)")
      ->check([](const std::string& v) -> std::string {
        const bool ok =
            !v.empty() && v.size() <= 40 && v.front() >= 'a' && v.front() <= 'z' &&
            v.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789-") == std::string::npos &&
            v.back() != '-';
        return ok ? "" : "expected a DNS label: lowercase letters, digits, '-', at most 40";
      });
  return [k8s, o]() -> std::optional<int> {
    if (!*k8s) return std::nullopt;
    Deploy d;
    try {
      ScenarioOverrides ov;
      ov.agents = o->agents;
      const RunConfig rc = load_scenario(o->scenario, ov);
      RegularFile file;
      d.scenario_text = read_regular_file(o->scenario, 1 << 20, file);
      if (file.problem != RegularFile::Problem::kNone) throw std::runtime_error(file.why);
      for (const AgentSpec& a : rc.agents) d.ids.push_back(a.id);
      d.domain = rc.transport.domain_id;
      const std::string keystore = o->keystore.empty() ? rc.transport.keystore : o->keystore;
      if (!keystore.empty() && !read_keystore(keystore, d)) return 2;
    } catch (const ScenarioError& e) {
      std::cerr << "swarm deploy k8s: " << e.what() << "\n";
      return 2;
    } catch (const std::exception& e) {
      std::cerr << "swarm deploy k8s: " << o->scenario << ": " << e.what() << "\n";
      return 2;
    }
    d.name = o->name;
    d.image = o->image;
    d.agents = static_cast<int>(d.ids.size());
    d.random_agents = o->agents > 0;
    std::error_code ec;
    std::filesystem::create_directories(o->out, ec);
    if (ec || !std::filesystem::is_directory(o->out, ec)) {
      std::cerr << "swarm deploy k8s: --out " << o->out << ": cannot make the directory"
                << (ec ? " (" + ec.message() + ")" : std::string()) << "\n";
      return 2;
    }
    for (const auto& [file, text] :
         {std::pair<std::string, std::string>{"quadswarm.yaml", d.kubernetes()},
          {"podman.yaml", d.podman()}}) {
      // Written aside, then renamed over what was there: never through a link, never half.
      const auto path = std::filesystem::path(o->out) / file;
      const auto aside = std::filesystem::path(o->out) / (file + ".tmp");
      std::filesystem::remove(aside, ec);
      std::ofstream f(aside, std::ios::trunc);
      f << text;
      f.close();
      bool written = static_cast<bool>(f);
      if (written) {
        std::filesystem::rename(aside, path, ec);
        written = !ec;
      }
      if (!written) {
        std::filesystem::remove(aside, ec);
        std::cerr << "swarm deploy k8s: --out " << o->out << ": cannot write " << path.string()
                  << "\n";
        return 2;
      }
    }
    std::cout << "swarm deploy k8s: " << d.agents << " agents, "
              << (d.secure() ? "secure (discovery by unicast)" : "2 Discovery Servers")
              << " and the supervisor in " << o->out << "/quadswarm.yaml (kubectl apply -f) and "
              << o->out << "/podman.yaml (podman kube play)\n";
    return 0;
  };
}

}  // namespace qswarm
