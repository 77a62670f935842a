"""swarm keys: a DDS-Security keystore for a scenario, and the check a secure run makes first.

Usage: python3 -m qswarm.keys --swarm BIN SCENARIO --out DIR [--days N] [--compose]
       python3 -m qswarm.keys --swarm BIN SCENARIO --check DIR
(the C++ `swarm keys` subcommand execs this; `swarm run --secure DIR` runs the check)

The layout follows ROS 2's sros2 convention: one certificate authority (EC prime256v1, SHA-256)
signs every identity and, as S/MIME (detached, text), the governance and every permissions file.

  DIR/ca.cert.pem                 the authority (identity CA and permissions CA)
  DIR/private/ca.key.pem          its key: keep it off the machines that fly
  DIR/governance.xml, .p7s        authentication required, discovery, liveliness and payload
                                  encrypted, read and write access controlled, no stranger admitted
  DIR/<name>/cert.pem, key.pem    one identity per agent id (agent-ID) and one for the supervisor
  DIR/<name>/permissions.xml, .p7s
      agent-ID     publish state and record samples only as agent ID (below), read the state
                   stream, claim ids
      supervisor   read the record stream only

An agent publishes into a partition of its own id beside its stream's partition (".../a3",
common/transport/interest.hpp); agent-ID's permissions let it publish state only into the run's
partition, its own ".../aID" and partitions that name no agent (".../q...", any name not
starting with "a"), and record samples only into the record partition and its ".../aID". Readers
take a sample keyed ID only from a writer in ".../aID" (common/dds/writer_registry.hpp), so the
holder of agent 3's key cannot publish as agent 5.

With --compose, for compose replicas that claim their ids at start (and so cannot be handed a
certificate for one in advance), it writes one `member` identity that every replica shares,
instead of agent-ID: a member may publish as any agent and claim ids, and a participant without
a certificate of this authority is kept out. The scenario's ids are not used; the supervisor's
identity is as above. `swarm run --secure` refuses such a keystore.

Keys are written with mode 0600 and never copied into a run directory.

Exit status: 0 when written (or, with --check, when the keystore holds what the scenario needs,
signed by its authority and valid now); 2 with `swarm keys: FILE: what is wrong` otherwise.
"""

import argparse
import datetime
import os
import shutil
import subprocess
import sys
import tempfile

from qswarm.binaries import BinaryError, inspect

PROG = "swarm keys"
SUBJECT_ORG = "qswarm"
# Every domain the port plan allows (0..22, common/transport/port_plan.hpp; DDS-Security names
# domain ranges).
DOMAINS = (0, 22)


class KeystoreError(Exception):
    def __init__(self, where, what):
        super().__init__(f"{where}: {what}")


def openssl(*args, cwd=None):
    r = subprocess.run(["openssl", *args], cwd=cwd, stdout=subprocess.PIPE,
                       stderr=subprocess.PIPE, text=True)
    if r.returncode != 0:
        lines = r.stderr.strip().splitlines()
        raise KeystoreError("openssl " + args[0], lines[-1] if lines else f"exit {r.returncode}")
    return r.stdout


def subject(name):
    # One name component: Fast DDS compares the grant's subject with the certificate's in RFC 2253
    # order (last component first), where two components would have to be written backwards.
    return f"CN={name}"


def governance_xml():
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-Security/20170801/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      <domains><id_range><min>{DOMAINS[0]}</min><max>{DOMAINS[1]}</max></id_range></domains>
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
"""


def rule(kind, topics, partitions):
    t = "".join(f"<topic>{x}</topic>" for x in topics)
    p = "".join(f"<partition>{x}</partition>" for x in partitions)
    return (f"        <{kind}><topics>{t}</topics><partitions>{p}</partitions></{kind}>\n")


# A run's partition: "qswarm-run-" and the run id's 16 hex digits, exactly (fnmatch patterns, as
# Fast DDS matches them: a '*' here would also match "qswarm-run-X/a5").
HEX16 = "[0-9a-f]" * 16
RUN = "qswarm-run-" + HEX16
RECORD = "qswarm-record-" + HEX16


def allow_rule(*rules):
    # Fast DDS checks a writer against the first allow_rule naming its topic, with the partitions
    # of every <publish> in that rule: one rule per topic keeps each topic's partitions its own.
    domains = (f"<domains><id_range><min>{DOMAINS[0]}</min><max>{DOMAINS[1]}</max></id_range>"
               "</domains>")
    return f"      <allow_rule>\n        {domains}\n{''.join(rules)}      </allow_rule>\n"


def agent_rules(agent_id):
    mine = f"a{agent_id}"
    return (allow_rule(rule("publish", ["qswarm/agent_state"],
                            [RUN, f"{RUN}/{mine}", f"{RUN}/[!a]*"]),
                       rule("subscribe", ["qswarm/agent_state", "qswarm/id_claim"],
                            ["qswarm-run-*"])) +
            allow_rule(rule("publish", ["qswarm/record"], [RECORD, f"{RECORD}/{mine}"])) +
            allow_rule(rule("publish", ["qswarm/id_claim"], [RUN])))


def member_rules():
    # Any agent's partitions: replicas learn their id only when they claim it.
    return allow_rule(rule("publish", ["qswarm/agent_state", "qswarm/id_claim"], ["qswarm-run-*"]),
                      rule("publish", ["qswarm/record"], ["qswarm-record-*"]),
                      rule("subscribe", ["qswarm/agent_state", "qswarm/id_claim"],
                           ["qswarm-run-*"]))


def permissions_xml(name, not_before, not_after):
    if name == "supervisor":
        rules = allow_rule(rule("subscribe", ["qswarm/record"], ["qswarm-record-*"]))
    elif name == MEMBER:
        rules = member_rules()
    else:
        rules = agent_rules(int(name.split("-", 1)[1]))
    stamp = "%Y-%m-%dT%H:%M:%S"
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-Security/20170801/omg_shared_ca_permissions.xsd">
  <permissions>
    <grant name="{name}">
      <subject_name>{subject(name)}</subject_name>
      <validity>
        <not_before>{not_before.strftime(stamp)}</not_before>
        <not_after>{not_after.strftime(stamp)}</not_after>
      </validity>
{rules}      <default>DENY</default>
    </grant>
  </permissions>
</dds>
"""


def write_private(path, text):
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(fd, "w") as f:
        f.write(text)


def sign(ca_dir, xml_path, p7s_path):
    openssl("smime", "-sign", "-text", "-in", xml_path, "-out", p7s_path,
            "-signer", os.path.join(ca_dir, "ca.cert.pem"),
            "-inkey", os.path.join(ca_dir, "private", "ca.key.pem"))


MEMBER = "member"


def identity_names(ids):
    return [f"agent-{i}" for i in ids] + ["supervisor"]


def is_compose(keystore):
    return os.path.isdir(os.path.join(keystore, MEMBER))


def generate(out, ids, days, compose=False):
    if os.path.exists(out) and os.listdir(out):
        raise KeystoreError(out, "exists and is not empty (a keystore is never overwritten)")
    parent = os.path.dirname(os.path.abspath(out))
    os.makedirs(parent, exist_ok=True)
    work = tempfile.mkdtemp(prefix=".keys-", dir=parent)
    try:
        os.makedirs(os.path.join(work, "private"), mode=0o700)
        ca_key = os.path.join(work, "private", "ca.key.pem")
        openssl("genpkey", "-algorithm", "EC", "-pkeyopt", "ec_paramgen_curve:prime256v1",
                "-out", ca_key)
        os.chmod(ca_key, 0o600)
        openssl("req", "-new", "-x509", "-sha256", "-key", ca_key, "-days", str(days),
                "-subj", "/CN=qswarm keystore CA/O=" + SUBJECT_ORG,
                "-out", os.path.join(work, "ca.cert.pem"))
        gov = os.path.join(work, "governance.xml")
        with open(gov, "w") as f:
            f.write(governance_xml())
        sign(work, gov, os.path.join(work, "governance.p7s"))
        now = datetime.datetime.now(datetime.timezone.utc).replace(microsecond=0)
        not_after = now + datetime.timedelta(days=days)
        # Fast DDS reads the permissions' times as local time: a day's margin for any time zone.
        now -= datetime.timedelta(days=1)
        for name in [MEMBER, "supervisor"] if compose else identity_names(ids):
            d = os.path.join(work, name)
            os.makedirs(d, mode=0o700)
            key = os.path.join(d, "key.pem")
            openssl("genpkey", "-algorithm", "EC", "-pkeyopt", "ec_paramgen_curve:prime256v1",
                    "-out", key)
            os.chmod(key, 0o600)
            csr = os.path.join(d, "req.csr")
            openssl("req", "-new", "-sha256", "-key", key, "-subj", f"/{subject(name)}",
                    "-out", csr)
            openssl("x509", "-req", "-sha256", "-in", csr, "-CA", os.path.join(work, "ca.cert.pem"),
                    "-CAkey", ca_key, "-CAcreateserial", "-days", str(days),
                    "-out", os.path.join(d, "cert.pem"))
            os.remove(csr)
            perm = os.path.join(d, "permissions.xml")
            with open(perm, "w") as f:
                f.write(permissions_xml(name, now, not_after))
            sign(work, perm, os.path.join(d, "permissions.p7s"))
        srl = os.path.join(work, "ca.cert.srl")
        if os.path.exists(srl):
            os.remove(srl)
        if os.path.exists(out):
            os.rmdir(out)
        os.rename(work, out)
        work = None
    finally:
        if work:
            shutil.rmtree(work, ignore_errors=True)


def check(keystore, ids):
    """Raises KeystoreError naming the first file that is missing, not signed by the keystore's
    authority, or not valid now."""
    if is_compose(keystore):
        raise KeystoreError(keystore, "a compose keystore (one member identity for replicas that "
                            "claim their ids); a secure run needs one identity per agent "
                            "(swarm keys SCENARIO --out DIR)")
    ca = os.path.join(keystore, "ca.cert.pem")
    need = [ca, os.path.join(keystore, "governance.p7s")]
    for name in identity_names(ids):
        need += [os.path.join(keystore, name, f)
                 for f in ("cert.pem", "key.pem", "permissions.p7s")]
    for path in need:
        if not os.path.isfile(path):
            raise KeystoreError(path, "missing (swarm keys SCENARIO --out DIR writes a keystore)")
    try:
        openssl("x509", "-in", ca, "-noout", "-checkend", "0")
    except KeystoreError:
        raise KeystoreError(ca, "not a certificate, or expired") from None
    for p7s in [os.path.join(keystore, "governance.p7s")] + [
            os.path.join(keystore, n, "permissions.p7s") for n in identity_names(ids)]:
        try:
            signed = openssl("smime", "-verify", "-in", p7s, "-CAfile", ca)
        except KeystoreError:
            raise KeystoreError(p7s, "not signed by the keystore's authority, or altered "
                                "since") from None
        # An agent's permissions must bind its id to its own partition: without that, readers
        # would bind its writers to nothing, or (older keystores) any agent's key.
        name = os.path.basename(os.path.dirname(p7s))
        if name.startswith("agent-") and f"<partition>{RUN}/a{name[6:]}</partition>" not in signed:
            raise KeystoreError(p7s, f"permissions that do not bind {name} to its own partition "
                                "(made by an older swarm keys?): make a new keystore")
    for name in identity_names(ids):
        cert = os.path.join(keystore, name, "cert.pem")
        try:
            openssl("verify", "-CAfile", ca, cert)
        except KeystoreError:
            raise KeystoreError(cert, "not issued by the keystore's authority, or "
                                "expired") from None
        key = os.path.join(keystore, name, "key.pem")
        try:
            cert_pub = openssl("x509", "-in", cert, "-noout", "-pubkey")
            key_pub = openssl("pkey", "-in", key, "-pubout")
        except KeystoreError:
            raise KeystoreError(key, "not a private key") from None
        if cert_pub.strip() != key_pub.strip():
            raise KeystoreError(key, f"does not belong to {cert}")


def main(argv=None):
    ap = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n")[0])
    ap.add_argument("--swarm", required=True, help="the swarm binary (for swarm inspect)")
    ap.add_argument("scenario")
    ap.add_argument("--out", help="write a new keystore here")
    ap.add_argument("--check", help="check this keystore against the scenario")
    ap.add_argument("--days", type=int, default=365, help="validity in days (default 365)")
    ap.add_argument("--compose", action="store_true",
                    help="one member identity for compose replicas instead of one per agent")
    try:
        a = ap.parse_args(argv)
    except SystemExit as e:
        return 0 if e.code == 0 else 2
    if a.compose and a.check:
        print(f"{PROG}: --compose goes with --out", file=sys.stderr)
        return 2
    if bool(a.out) == bool(a.check):
        print(f"{PROG}: give --out DIR or --check DIR", file=sys.stderr)
        return 2
    if not 1 <= a.days <= 36500:
        print(f"{PROG}: --days: expected 1 to 36500, got {a.days}", file=sys.stderr)
        return 2
    if shutil.which("openssl") is None:
        print(f"{PROG}: openssl is not installed (tools/setup.sh installs it)", file=sys.stderr)
        return 2
    try:
        ids = [int(agent["id"]) for agent in inspect(a.swarm, a.scenario)["agents"]]
        if a.out and a.compose:
            generate(a.out, ids, a.days, compose=True)
            print(f"{PROG}: compose keystore (a member identity and the supervisor) in {a.out}")
        elif a.out:
            generate(a.out, ids, a.days)
            print(f"{PROG}: keystore for {len(ids)} agents and the supervisor in {a.out}")
        else:
            check(a.check, ids)
    except (BinaryError, KeystoreError) as e:
        print(f"{PROG}: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
