// `swarm deploy k8s SCENARIO [--agents N] --out DIR`: the swarm as Kubernetes manifests
// (DIR/quadswarm.yaml), and the same containers as one Pod per process for `podman kube play`
// (DIR/podman.yaml), which runs no StatefulSet, Service or Job. The size is typed once, here.
//
// Agents: a StatefulSet (pod quadswarm-agent-K flies the scenario's K-th agent) behind a headless
// Service. Discovery: two Discovery Servers, each a Deployment behind a ClusterIP Service of its
// own, listed by every process in one order (a client must know each server's GUID prefix, so
// replicas behind one Service cannot work in Fast DDS 2.9; docs/hosts.md). Supervisor: a Job whose
// exit code is the run's, recording onto a PersistentVolumeClaim.
#include <CLI/CLI.hpp>

#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "common/record/json_writer.hpp"
#include "common/scenario/scenario.hpp"
#include "common/transport/regular_file.hpp"
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

struct Deploy {
  std::string name = "quadswarm", image, scenario_text;
  int agents = 0;
  std::vector<AgentId> ids;
  bool random_agents = false;
  std::uint32_t domain = 0;

  std::string server_name(int i) const { return name + "-discovery-" + std::to_string(i); }
  std::string servers() const {
    std::string list;
    for (int i = 0; i < kServers; ++i)
      list += (i ? "," : "") + server_name(i) + ":" + std::to_string(kServerPort);
    return list;
  }
  // One container, as every manifest runs it: `command` is a shell line (the agents read their
  // ordinal from the pod's name).
  std::string container(const std::string& role, const std::string& command, int indent,
                        bool runs_volume) const {
    std::ostringstream c;
    c << "- name: " << role << "\n"
      << "  image: " << quoted(image) << "\n"
      << "  imagePullPolicy: IfNotPresent\n"
      << "  command: [\"/bin/sh\", \"-c\", " << quoted(command) << "]\n"
      << "  env:\n"
      << "  - name: QSWARM_DISCOVERY_SERVER\n"
      << "    value: " << quoted(servers()) << "\n";
    if (random_agents)
      c << "  - name: QSWARM_AGENTS\n    value: " << quoted(std::to_string(agents)) << "\n";
    c << "  volumeMounts:\n"
      << "  - name: scenario\n    mountPath: /etc/quadswarm\n    readOnly: true\n";
    if (runs_volume) c << "  - name: runs\n    mountPath: /runs\n";
    return indented(c.str(), indent);
  }
  std::string volumes(int indent, bool runs_volume) const {
    std::ostringstream v;
    v << "volumes:\n"
      << "- name: scenario\n  configMap:\n    name: " << name << "-scenario\n";
    if (runs_volume)
      v << "- name: runs\n  persistentVolumeClaim:\n    claimName: " << name << "-runs\n";
    return indented(v.str(), indent);
  }
  std::string agent_command() const {
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
           "--new-run-in /runs --start-timeout 300";
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
  std::string labels(const std::string& component, int indent) const {
    return indented("labels:\n  app: " + name + "\n  component: " + component + "\n", indent);
  }

  std::string kubernetes() const {
    std::ostringstream y;
    y << "# " << name << ": " << agents
      << " agents (swarm deploy k8s). kubectl apply -f this file;\n"
      << "# the Job " << name << "-supervisor ends with the run's verdict, its record on the claim "
      << name << "-runs.\n";
    y << config_map() << "---\n" << claim();
    for (int i = 0; i < kServers; ++i) {
      const std::string s = server_name(i);
      y << "---\napiVersion: v1\nkind: Service\nmetadata:\n  name: " << s << "\nspec:\n"
        << "  selector:\n    app: " << name << "\n    component: " << s << "\n"
        << "  ports:\n  - name: discovery\n    protocol: UDP\n    port: " << kServerPort << "\n";
      y << "---\napiVersion: apps/v1\nkind: Deployment\nmetadata:\n  name: " << s << "\nspec:\n"
        << "  replicas: 1\n  selector:\n    matchLabels:\n      app: " << name
        << "\n      component: " << s << "\n  template:\n    metadata:\n"
        << labels(s, 6) << "    spec:\n"
        << pod_security(6) << "      containers:\n"
        << container("discovery", server_command(i), 6, false) << volumes(6, false);
    }
    y << "---\napiVersion: v1\nkind: Service\nmetadata:\n  name: " << name << "-agents\nspec:\n"
      << "  clusterIP: None\n  publishNotReadyAddresses: true\n"
      << "  selector:\n    app: " << name << "\n    component: agent\n";
    y << "---\napiVersion: apps/v1\nkind: StatefulSet\nmetadata:\n  name: " << name
      << "-agent\nspec:\n  serviceName: " << name << "-agents\n  replicas: " << agents
      << "\n  podManagementPolicy: Parallel\n  selector:\n    matchLabels:\n      app: " << name
      << "\n      component: agent\n  template:\n    metadata:\n"
      << labels("agent", 6) << "    spec:\n"
      << pod_security(6) << "      containers:\n"
      << container("agent", agent_command(), 6, false) << volumes(6, false);
    y << "---\napiVersion: batch/v1\nkind: Job\nmetadata:\n  name: " << name
      << "-supervisor\nspec:\n  backoffLimit: 0\n  template:\n    metadata:\n"
      << labels("supervisor", 6) << "    spec:\n      restartPolicy: Never\n"
      << pod_security(6) << "      containers:\n"
      << container("supervisor", supervisor_command(), 6, true) << volumes(6, true);
    return y.str();
  }

  std::string pod(const std::string& pod_name, const std::string& component,
                  const std::string& role, const std::string& command, bool runs_volume) const {
    return "---\napiVersion: v1\nkind: Pod\nmetadata:\n  name: " + pod_name + "\n" +
           labels(component, 2) + "spec:\n  restartPolicy: Never\n" + pod_security(2) +
           "  containers:\n" + container(role, command, 2, runs_volume) + volumes(2, runs_volume);
  }
  std::string podman() const {
    std::ostringstream y;
    y << "# " << name << ": the containers of quadswarm.yaml as one Pod per process, for\n"
      << "# podman kube play (it runs no StatefulSet, Service or Job).\n";
    y << config_map() << "---\n" << claim();
    for (int i = 0; i < kServers; ++i)
      y << pod(server_name(i), server_name(i), "discovery", server_command(i), false);
    y << pod(name + "-supervisor", "supervisor", "supervisor", supervisor_command(), true);
    for (int k = 0; k < agents; ++k)
      y << pod(name + "-agent-" + std::to_string(k), "agent", "agent", agent_command(), false);
    return y.str();
  }
};

}  // namespace

Command add_deploy_command(CLI::App& app) {
  struct Options {
    std::string scenario, out, image = "localhost/qswarm:latest", name = "quadswarm";
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
      if (!rc.transport.keystore.empty()) {
        std::cerr << "swarm deploy k8s: scenario field 'transport.keystore': secure swarms are "
                     "not deployed yet (docs/hosts.md)\n";
        return 2;
      }
      RegularFile file;
      d.scenario_text = read_regular_file(o->scenario, 1 << 20, file);
      if (file.problem != RegularFile::Problem::kNone) throw std::runtime_error(file.why);
      for (const AgentSpec& a : rc.agents) d.ids.push_back(a.id);
      d.domain = rc.transport.domain_id;
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
    std::cout << "swarm deploy k8s: " << d.agents << " agents, 2 Discovery Servers and the "
              << "supervisor in " << o->out << "/quadswarm.yaml (kubectl apply -f) and " << o->out
              << "/podman.yaml (podman kube play)\n";
    return 0;
  };
}

}  // namespace qswarm
