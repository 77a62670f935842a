// ctest label `hosts`: the manifests `swarm deploy k8s` writes validate against the Kubernetes
// JSON schema (npm's kubernetes-models), and say what the swarm needs: a StatefulSet of N agents
// behind a headless Service, two Discovery Servers each behind its own Service and listed by
// every process in one order, a Job for the supervisor writing onto a PersistentVolumeClaim, and
// the size typed once; secure, each pod holding only its own identity. A manifest broken on
// purpose fails the same validation, so it can fail.
//
// Usage: node manifests_test.mjs (QSWARM_BIN_DIR, QSWARM_NODE_MODULES, QSWARM_SOURCE_DIR set by
// ctest). Exit 77 when npm's packages are missing, unless CI is set (then 1).
import { execFileSync } from "node:child_process";
import { mkdtempSync, readFileSync, rmSync, writeFileSync } from "node:fs";
import { createRequire } from "node:module";
import { tmpdir } from "node:os";
import path from "node:path";

const bin = process.env.QSWARM_BIN_DIR;
const modules = process.env.QSWARM_NODE_MODULES;
const require = createRequire(path.join(modules, "noop.js"));
let YAML, models;
try {
  YAML = require("yaml");
  models = {
    v1: require("kubernetes-models/v1"),
    "apps/v1": require("kubernetes-models/apps/v1"),
    "batch/v1": require("kubernetes-models/batch/v1"),
  };
} catch (e) {
  console.log(`${process.env.CI ? "FAIL (CI)" : "SKIPPED"}: npm packages missing (${e.message})`);
  process.exit(process.env.CI ? 1 : 77);
}

let failed = 0;
const check = (what, ok, got = "") => {
  console.log(`${ok ? "ok" : "FAIL"}: ${what}${got === "" ? "" : ` (${got})`}`);
  if (!ok) failed = 1;
};
// Every document against its kind's schema: the list of problems ("" when none).
const problems = (docs) => {
  const out = [];
  for (const doc of docs) {
    const Kind = models[doc.apiVersion]?.[doc.kind];
    if (!Kind) {
      out.push(`${doc.apiVersion} ${doc.kind}: no such kind`);
      continue;
    }
    try {
      new Kind(doc).validate();
    } catch (e) {
      out.push(`${doc.kind} ${doc.metadata?.name}: ${e.message.split("\n")[0]}`);
    }
  }
  return out;
};

const work = mkdtempSync(path.join(tmpdir(), "qswarm-manifests-"));
try {
  const scenario = path.join(work, "s.txtpb");
  writeFileSync(scenario, 'name: "k"\nweight { policy: UNWEIGHTED }\n' +
    "topology { policy: PROXIMITY threshold_m: 50 }\nseed: 4\ntransport { domain_id: 7 }\n");
  for (const [n, extra] of [[40, ["--agents", "40"]], [4, []]]) {
    const file = n === 4 ? path.join(process.env.QSWARM_SOURCE_DIR, "scenarios", "demo.txtpb")
                         : scenario;
    const out = path.join(work, `d${n}`);
    execFileSync(path.join(bin, "swarm"), ["deploy", "k8s", file, ...extra, "--out", out]);
    for (const name of ["quadswarm.yaml", "podman.yaml"]) {
      const docs = YAML.parseAllDocuments(readFileSync(path.join(out, name), "utf8"))
        .map((d) => d.toJS());
      const bad = problems(docs);
      check(`${n} agents: ${name}'s ${docs.length} documents validate`, bad.length === 0,
            bad.join("; "));
      const byKind = (k) => docs.filter((d) => d.kind === k);
      const containers = docs.flatMap((d) =>
        (d.spec?.template?.spec ?? d.spec)?.containers ?? []);
      const servers = new Set(containers.map((c) =>
        c.env.find((e) => e.name === "QSWARM_DISCOVERY_SERVER")?.value));
      check(`${n} agents: ${name}: every process lists the same two servers`,
            servers.size === 1 && [...servers][0].split(",").length === 2, [...servers].join(" "));
      if (name === "quadswarm.yaml") {
        const sts = byKind("StatefulSet");
        check(`${n} agents: one StatefulSet of ${n}`, sts.length === 1 && sts[0].spec.replicas === n,
              sts[0]?.spec.replicas);
        const headless = byKind("Service").find((s) => s.metadata.name === sts[0].spec.serviceName);
        check(`${n} agents: its headless Service`, headless?.spec.clusterIP === "None" &&
              headless.spec.publishNotReadyAddresses === true);
        check(`${n} agents: two Discovery Server Deployments, each behind a Service`,
              byKind("Deployment").length === 2 &&
              byKind("Service").filter((s) => s.spec.clusterIP !== "None").length === 2);
        const job = byKind("Job")[0];
        check(`${n} agents: the supervisor is a Job that never retries, on the claim`,
              job?.spec.backoffLimit === 0 &&
              job.spec.template.spec.volumes.some((v) => v.persistentVolumeClaim) &&
              byKind("PersistentVolumeClaim").length === 1);
      } else {
        check(`${n} agents: podman.yaml has a Pod per process`,
              byKind("Pod").length === n + 3, byKind("Pod").length);
      }
      // The size is typed once: what every process reads says n, nowhere another number.
      const sizes = new Set(containers.flatMap((c) => c.env)
        .filter((e) => e.name === "QSWARM_AGENTS").map((e) => e.value));
      check(`${n} agents: ${name}: the size reaches the processes once`,
            n === 4 ? sizes.size === 0 : sizes.size === 1 && sizes.has("40"), [...sizes]);
    }
  }
  // What the pods read is the scenario as written, whatever its first line's indentation, and
  // text given on the command line stays what it was (a quote, a line break).
  const odd = path.join(work, "odd.txtpb");
  const oddText = '  # indented first line\nname: "odd"\nagents { id: 1 }\n';
  writeFileSync(odd, oddText);
  execFileSync(path.join(bin, "swarm"), ["deploy", "k8s", odd, "--out", path.join(work, "odd"),
                                         "--image", 'img\n"x']);
  const oddDocs = YAML.parseAllDocuments(
    readFileSync(path.join(work, "odd", "quadswarm.yaml"), "utf8"));
  check("an indented first line: the manifest parses",
        oddDocs.every((d) => d.errors.length === 0), oddDocs.flatMap((d) => d.errors).join("; "));
  const oddJs = oddDocs.map((d) => d.toJS());
  check("the ConfigMap holds the scenario byte for byte",
        oddJs[0].data["scenario.txtpb"] === oddText, JSON.stringify(oddJs[0].data));
  check("an --image with a quote and a line break is carried as given",
        oddJs.find((d) => d.kind === "Job").spec.template.spec.containers[0].image === 'img\n"x');
  // Secure: the keystore as Secrets, each agent pod (a StatefulSet of one) mounting only its own
  // identity and the shared files; no server; the headless Service names agents and supervisor.
  const demo = path.join(process.env.QSWARM_SOURCE_DIR, "scenarios", "demo.txtpb");
  const keys = path.join(work, "keys");
  execFileSync(path.join(bin, "swarm"), ["keys", demo, "--out", keys]);
  execFileSync(path.join(bin, "swarm"), ["deploy", "k8s", demo, "--keystore", keys,
                                         "--out", path.join(work, "secure")]);
  for (const name of ["quadswarm.yaml", "podman.yaml"]) {
    const docs = YAML.parseAllDocuments(readFileSync(path.join(work, "secure", name), "utf8"))
      .map((d) => d.toJS());
    const bad = problems(docs);
    check(`secure: ${name}'s ${docs.length} documents validate`, bad.length === 0, bad.join("; "));
    const podman = name === "podman.yaml";
    const holder = podman ? "ConfigMap" : "Secret";
    const keyObjects = docs.filter((d) => d.kind === holder && d.metadata.name !== "quadswarm-scenario");
    const text = (d, k) => (podman ? d.data[k] : Buffer.from(d.data[k], "base64").toString());
    const identities = ["agent-1", "agent-2", "agent-3", "agent-4", "supervisor"];
    check(`secure: ${name}: the shared files and one ${holder} per identity`,
          keyObjects.length === 6 && identities.every((i) => {
            const o = keyObjects.find((d) => d.metadata.name === `quadswarm-key-${i}`);
            return o && Object.keys(o.data).sort().join() === "cert.pem,key.pem,permissions.p7s" &&
              text(o, "key.pem") === readFileSync(path.join(keys, i, "key.pem"), "utf8");
          }), keyObjects.map((d) => d.metadata.name).join(" "));
    const trust = keyObjects.find((d) => d.metadata.name === "quadswarm-trust");
    check(`secure: ${name}: the authority's key stays home`,
          trust && Object.keys(trust.data).sort().join() === "ca.cert.pem,governance.p7s" &&
          !readFileSync(path.join(work, "secure", name), "utf8").includes(
            readFileSync(path.join(keys, "private", "ca.key.pem"), "utf8").split("\n")[1]));
    const specs = docs.filter((d) => ["StatefulSet", "Job", "Pod"].includes(d.kind))
      .map((d) => ({ name: d.metadata.name, spec: d.spec.template?.spec ?? d.spec }));
    const own = specs.map(({ name: n, spec }) => {
      const mounted = spec.volumes.map((v) => v.secret?.secretName ?? v.configMap?.name)
        .filter((v) => v && v !== "quadswarm-scenario").sort().join();
      const who = n.endsWith("supervisor") ? "supervisor"
                                           : `agent-${Number(n.split("-").slice(-1)[0]) + 1}`;
      return mounted === `quadswarm-key-${who},quadswarm-trust` ? "" : `${n}: ${mounted}`;
    }).filter((x) => x);
    check(`secure: ${name}: each pod mounts only its own identity`, specs.length === 5 && !own.length,
          own.join("; "));
    const env = specs.flatMap(({ spec }) => spec.containers.flatMap((c) => c.env ?? []));
    check(`secure: ${name}: no Discovery Server`,
          !docs.some((d) => d.metadata.name.includes("discovery")) &&
          !env.some((e) => e.name === "QSWARM_DISCOVERY_SERVER"));
    if (!podman) {
      const sts = docs.filter((d) => d.kind === "StatefulSet");
      check("secure: a StatefulSet of one per agent",
            sts.length === 4 && sts.every((d) => d.spec.replicas === 1));
      const headless = docs.find((d) => d.kind === "Service");
      const peers = specs.filter(({ spec }) => spec.containers[0].command[2].includes(
        `--peer-hosts ${headless.metadata.name}`));
      check("secure: every process finds the others at the headless Service, which selects them",
            peers.length === 5 && headless.spec.selector.peer === "dds" &&
            docs.filter((d) => d.spec?.template?.metadata?.labels?.peer === "dds").length === 5);
    }
  }
  // The size typed once, secure too: keys for --agents 5 random agents, deployed with the same.
  const keys5 = path.join(work, "keys5");
  execFileSync(path.join(bin, "swarm"), ["keys", scenario, "--agents", "5", "--out", keys5]);
  execFileSync(path.join(bin, "swarm"), ["deploy", "k8s", scenario, "--agents", "5", "--keystore",
                                         keys5, "--out", path.join(work, "secure5")]);
  const five = YAML.parseAllDocuments(readFileSync(path.join(work, "secure5", "quadswarm.yaml"),
                                                   "utf8")).map((d) => d.toJS());
  check("secure, --agents 5: five agents, each its own key",
        five.filter((d) => d.kind === "StatefulSet").length === 5 &&
        five.filter((d) => d.kind === "Secret").length === 7 && problems(five).length === 0);
  // The validator can fail: a StatefulSet whose replicas is text, and a Pod without containers.
  const docs = YAML.parseAllDocuments(readFileSync(path.join(work, "d4", "quadswarm.yaml"), "utf8"))
    .map((d) => d.toJS());
  const sts = docs.find((d) => d.kind === "StatefulSet");
  sts.spec.replicas = "four";
  check("a StatefulSet with replicas: \"four\" fails", problems([sts]).length === 1);
  check("a Pod without containers fails",
        problems([{ apiVersion: "v1", kind: "Pod", metadata: { name: "p" }, spec: {} }]).length === 1);
  // Bad input from a person: exit 2, naming it.
  const out = ["--out", path.join(work, "bad")];
  for (const args of [["--agents", "0", ...out], ["--name", "Bad_Name", ...out],
                      ["--out", "/proc/forbidden/x", "--agents", "3"],
                      ["--out", scenario, "--agents", "3"],
                      ["--keystore", path.join(work, "none"), "--agents", "3", ...out],
                      ["--keystore", keys, "--agents", "5", ...out]]) {
    let code = 0, err = "";
    try {
      execFileSync(path.join(bin, "swarm"), ["deploy", "k8s", scenario, ...args],
                   { stdio: "pipe" });
    } catch (e) {
      code = e.status;
      err = e.stderr.toString();
    }
    check(`swarm deploy k8s ${args.slice(0, 2).join(" ")} exits 2 naming it`,
          code === 2 && err.includes(args[0]), `${code}: ${err.trim().split("\n")[0]}`);
  }
} finally {
  rmSync(work, { recursive: true, force: true });
}
process.exit(failed);
