#!/usr/bin/env python3
"""Checks deploy/kube/fleet.yaml without a cluster (none runs here): every Deployment and StatefulSet
non-root with a read-only root filesystem and no capabilities, requests and limits, liveness on
/livez and readiness on /readyz at the port the service serves them (FLEET_METRICS_PORT), images
tagged with the project version; the fleet manager one replica, strategy Recreate, its database on
the PersistentVolumeClaim; the adapter likewise with its event log (--events-log) on a claim; a traffic manager (one replica, the ConfigMap's site): every robot agent
drives only what it releases; the robot agents one StatefulSet whose pods take their robots from the
ConfigMap fleet-robots by their ordinal (an entry per replica, each robot once, at a station of the
site; no --robot in the manifest's arguments); every ConfigMap, Secret, claim and config file
referenced exists; every DDS peer is a headless Service selecting a workload or an agent pod's name;
a NetworkPolicy admits the ops ports from monitoring pods and the nodes only, and liveness probes
survive a busy node; the shipped site passes `fleetctl site check`. Secure by default: every
container requires DDS Security (FLEET_DDS_SECURITY=required, its identity's security.xml after the
cluster profile, FLEET_DDS_SECURITY_DIR its mount of the Secret fleet-dds, whose items rebuild the
identity's folder from keys that `scripts/dds-security kube-secret` makes; the Secret itself not in
the file, which would overwrite the site's), the adapter https (FLEET_WMS_TLS=required, its
certificate and key among its items); deploy/kube/fleet.dev.yaml is what scripts/kube-dev-variant
makes of fleet.yaml (development only: no fleet-dds, security off). Then the closest to running
them that this machine offers: each Deployment's binary from BUILD_DIR, and the StatefulSet's
command for each ordinal, started with the manifest's arguments and environment, the ConfigMaps'
and Secret's files and a site made by `scripts/dds-security site`, each pod's items of fleet-dds
laid out as its mount (paths moved to a temporary folder, DDS on loopback with Security), which
must come up live (the fleet manager and the traffic manager ready), the adapter answering https
with the site's certificate, each agent driving its ordinal's robot; an ordinal without an entry
exits 2.
deploy/kube/fleet.postgres.yaml under the same rules (not run here: it needs its database; `ctest -R
kube_play_postgres` plays it), where the fleet managers and the WMS adapters are StatefulSets of two
replicas (Parallel) whose pods' names are DDS peers, every such name under a headless Service that
publishes pods not ready, the managers ready when live (/readyz is the active one's only); and
beyond them: the Secret fleet-postgres the only place of the password, its url (no password in it)
the managers' FLEET_STORE and the adapters' FLEET_EVENTS_LOG, its password their PGPASSWORD and the
database's FLEET_PG_PASSWORD, no URL or password in a literal and no store of their own; the
database one replica of a StatefulSet whose volumeClaimTemplate is mounted at the data directory's
parent, hardened as the services, probed by pg_isready, behind the Service the url names, reachable
from the managers and adapters only (NetworkPolicy); a PodDisruptionBudget of one for each pair; and
every other document, and the manager's and adapter's pods but for their store, as fleet.yaml has
them.
Usage: kube_manifests_check.py SOURCE_DIR BUILD_DIR"""
import base64
import copy
import http.client as httpclient
import json
import os
import re
import socket
import ssl
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.parse
import urllib.request

import yaml

src, build = sys.argv[1], sys.argv[2]
fleetctl = os.path.join(build, "services/fleetctl/fleetctl")
binaries = {"fleet-manager": "services/fleet_manager/fleet_manager", "wms-adapter": "services/wms_adapter/wms_adapter",
            "risk-map": "services/risk_map/risk_map", "robot-agent": "services/robot_agent/robot_agent",
            "traffic-manager": "services/traffic_manager/traffic_manager"}
DDS_SECRET, DDS_DIR, PG_SECRET = "fleet-dds", "/run/fleet-dds", "fleet-postgres"
version = re.search(r"project\(fleet VERSION ([0-9.]+)", open(os.path.join(src, "CMakeLists.txt")).read()).group(1)
problems = []
current = "deploy/kube/fleet.yaml"  # the file the problems found are in


def check(cond, what):
    if not cond:
        problems.append(f"{current}: {what}")


# The keys of the Secret fleet-dds as scripts/dds-security makes them, for a site of its own.
site_tmp = tempfile.TemporaryDirectory()
site_dir = os.path.join(site_tmp.name, "dds")
r = subprocess.run([os.path.join(src, "scripts/dds-security"), "site", site_dir, "wms-adapter.fleet.svc"],
                   capture_output=True, text=True, timeout=120)
check(r.returncode == 0, f"scripts/dds-security site failed: {r.stderr[-300:]}")
r = subprocess.run([os.path.join(src, "scripts/dds-security"), "kube-secret", site_dir], capture_output=True,
                   text=True, timeout=60)
check(r.returncode == 0, f"scripts/dds-security kube-secret failed: {r.stderr[-300:]}")
dds_secret = yaml.safe_load(r.stdout) if r.returncode == 0 else {"metadata": {}, "data": {}}
check(dds_secret["metadata"].get("name") == DDS_SECRET and dds_secret["metadata"].get("namespace") == "fleet",
      f"scripts/dds-security kube-secret makes {dds_secret['metadata']}, not {DDS_SECRET} in namespace fleet")
dds_files = {k: base64.b64decode(v) for k, v in dds_secret.get("data", {}).items()}
check("ca.key" not in dds_files, "the Secret holds the site CA's key")


def static_checks(name):
    """The rules of the docstring for deploy/kube/NAME; returns its documents by kind and name,
    each workload's items of fleet-dds, and the robots of each entry of fleet-robots."""
    global current
    current = f"deploy/kube/{name}"
    postgres = name == "fleet.postgres.yaml"
    docs = [d for d in yaml.safe_load_all(open(os.path.join(src, current))) if d]
    by_kind = {}
    for d in docs:
        by_kind.setdefault(d["kind"], {})[d["metadata"]["name"]] = d
    configmaps = by_kind.get("ConfigMap", {})
    secrets = by_kind.get("Secret", {})
    claims = by_kind.get("PersistentVolumeClaim", {})
    services = by_kind.get("Service", {})
    deployments = by_kind.get("Deployment", {})
    statefulsets = by_kind.get("StatefulSet", {})
    workloads = {**deployments, **statefulsets}
    check(set(workloads) >= {"fleet-manager", "wms-adapter", "risk-map", "traffic-manager", "robot-agent"},
          f"workloads: {sorted(workloads)}")
    # The robot agents one StatefulSet; on PostgreSQL the managers and adapters too (two replicas with
    # the pods' stable names as DDS peers), and the database.
    want = {"robot-agent", "fleet-manager", "wms-adapter", "postgres"} if postgres else {"robot-agent"}
    check(set(statefulsets) == want and not set(deployments) & want,
          f"StatefulSets {sorted(statefulsets)}, not {sorted(want)}")
    check(DDS_SECRET not in secrets, f"Secret {DDS_SECRET} in the file: an apply would overwrite the site's "
          "(scripts/dds-security kube-secret makes it)")

    dds_items = {}  # workload -> {path in the mount: key}

    for name, dep in workloads.items():
        spec = dep["spec"]
        pod = spec["template"]["spec"]
        labels = spec["template"]["metadata"]["labels"]
        check(spec["selector"]["matchLabels"].items() <= labels.items(), f"{name}: selector does not match its pods")
        vols = {v["name"]: v for v in pod.get("volumes", [])}
        for v in vols.values():
            if "configMap" in v:
                check(v["configMap"]["name"] in configmaps, f"{name}: no ConfigMap {v['configMap']['name']}")
            if "secret" in v and v["secret"]["secretName"] == DDS_SECRET:
                items = {i["path"]: i["key"] for i in v["secret"].get("items", [])}
                check(items and all(k in dds_files for k in items.values()),
                      f"{name}: items of {DDS_SECRET} that scripts/dds-security kube-secret does not make: "
                      f"{sorted(k for k in items.values() if k not in dds_files)} (or no items: every key would be mounted)")
                check(v["secret"].get("defaultMode") == 0o400, f"{name}: {DDS_SECRET} not mode 0400")
                dds_items[name] = items
            elif "secret" in v:
                check(v["secret"]["secretName"] in secrets, f"{name}: no Secret {v['secret']['secretName']}")
            if "persistentVolumeClaim" in v:
                check(v["persistentVolumeClaim"]["claimName"] in claims, f"{name}: no claim")
        for c in pod["containers"]:
            for e in c.get("env", []):
                ref = e.get("valueFrom", {}).get("secretKeyRef")
                check(not ref or ref["key"] in {**secrets.get(ref["name"], {}).get("stringData", {}),
                                                **secrets.get(ref["name"], {}).get("data", {})},
                      f"{name}: env {e['name']} from {ref} of no Secret in the file")
        if name == "postgres":  # not a service of ours: postgres_variant_checks
            continue
        for c in pod["containers"]:
            where = f"{name}/{c['name']}"
            sc = c.get("securityContext", {})
            check(sc.get("runAsNonRoot") is True and sc.get("runAsUser", 0) != 0, f"{where}: may run as root")
            check(sc.get("readOnlyRootFilesystem") is True, f"{where}: root filesystem writable")
            check(sc.get("allowPrivilegeEscalation") is False, f"{where}: privilege escalation allowed")
            check(sc.get("capabilities", {}).get("drop") == ["ALL"], f"{where}: capabilities not dropped")
            res = c.get("resources", {})
            check({"cpu", "memory"} <= set(res.get("requests", {})) and {"cpu", "memory"} <= set(res.get("limits", {})),
                  f"{where}: requests/limits incomplete")
            check(c["image"].endswith(":" + version), f"{where}: image {c['image']} not tagged {version}")
            env = {e["name"]: e.get("value") for e in c.get("env", [])}
            ports = {p["name"]: p["containerPort"] for p in c.get("ports", [])}
            check(c.get("image", "").split(":")[0] == f"localhost/fleet-{name}", f"{where}: image {c.get('image')}")
            check(str(ports.get("ops")) == env.get("FLEET_METRICS_PORT"), f"{where}: ops port != FLEET_METRICS_PORT")
            check(env.get("FLEET_METRICS_HOST") == "0.0.0.0", f"{where}: ops port only on loopback (the kubelet probes the pod IP)")
            # Two managers on PostgreSQL: /readyz is the active one's only, and a replica never ready
            # would stall the StatefulSet's rolling updates: ready when live.
            ready = "/livez" if postgres and name == "fleet-manager" else "/readyz"
            for probe, path in (("livenessProbe", "/livez"), ("readinessProbe", ready)):
                g = c.get(probe, {}).get("httpGet", {})
                check(g.get("path") == path and g.get("port") in ("ops", ports.get("ops")), f"{where}: {probe} not {path} on ops")
            live = c.get("livenessProbe", {})
            # A busy node answers late: a restart only after a minute of probes failing, each given 10 s.
            check(live.get("timeoutSeconds", 1) >= 10 and live.get("timeoutSeconds", 1) * live.get("failureThreshold", 3) >= 60,
                  f"{where}: livenessProbe restarts a merely busy pod (timeoutSeconds x failureThreshold < 60 s)")
            mounts = {m["mountPath"]: m for m in c.get("volumeMounts", [])}
            for m in mounts.values():
                check(m["name"] in vols, f"{where}: mount of unknown volume {m['name']}")
            uri = env.get("CYCLONEDDS_URI", "").split(",")
            check(uri[0] == "file:///etc/fleet/cyclonedds.xml" and "/etc/fleet" in mounts, f"{where}: DDS config not mounted")
            # Secure by default: the identity's security.xml after the profile, its folder from fleet-dds.
            dds = mounts.get(DDS_DIR)
            items = dds_items.get(name, {}) if dds and vols.get(dds["name"], {}).get("secret") else {}
            ident = uri[1][len(f"file://{DDS_DIR}/"):-len("/security.xml")] if len(uri) == 2 else ""
            check(env.get("FLEET_DDS_SECURITY") == "required", f"{where}: FLEET_DDS_SECURITY is not required")
            check(env.get("FLEET_DDS_SECURITY_DIR") == DDS_DIR and dds is not None and dds.get("readOnly") is True,
                  f"{where}: FLEET_DDS_SECURITY_DIR is not {DDS_DIR}, the read-only mount of {DDS_SECRET}")
            check(ident != "" and uri[1] == f"file://{DDS_DIR}/{ident}/security.xml",
                  f"{where}: CYCLONEDDS_URI {env.get('CYCLONEDDS_URI')} names no identity's security.xml")
            need = ["ca.pem", "crl.pem", "governance.p7s"] + [f"{ident}/{f}" for f in
                                                               ("security.xml", "cert.pem", "key.pem", "permissions.p7s")]
            check(all(items.get(p) == p.replace("/", ".") for p in need),
                  f"{where}: the items of {DDS_SECRET} do not rebuild {need} (identity {ident})")
            check(not [k for k in items.values() if k.endswith(".key.pem") and not k.startswith((ident + ".", "https."))],
                  f"{where}: mounts another identity's key")
            args = c.get("args", [])
            for flag in ("--config", "--site"):
                if flag in args:
                    f = args[args.index(flag) + 1]
                    check(f.startswith("/etc/fleet/") and os.path.basename(f) in configmaps["fleet-config"]["data"],
                          f"{where}: {flag} {f} not in the ConfigMap")
            if name in ("fleet-manager", "wms-adapter") and postgres:
                # The URL from the Secret (checked by postgres_variant_checks), no file of their own.
                check(spec.get("replicas") == 2 and spec.get("serviceName") == f"{name}-dds"
                      and spec.get("podManagementPolicy") == "Parallel",
                      f"{name}: not two replicas started together whose pods {name}-dds names")
                check(not {"--db", "--store", "--events-log"} & set(args) and "/var/lib/fleet" not in mounts,
                      f"{name}: a store or an event log of its own ({args})")
            elif name == "fleet-manager":
                check(spec.get("replicas") == 1, "fleet-manager: more than one replica (one SQLite writer)")
                check(spec.get("strategy", {}).get("type") == "Recreate", "fleet-manager: not strategy Recreate")
                db = args[args.index("--db") + 1]
                m = mounts.get(os.path.dirname(db))
                check(m is not None and "persistentVolumeClaim" in vols[m["name"]], "fleet-manager: database not on the claim")
            if name == "traffic-manager":
                check(spec.get("replicas") == 1, "traffic-manager: not one replica (two would release the same roadmap)")
                cfg = args[args.index("--config") + 1] if "--config" in args else ""
                tm = json.loads(configmaps["fleet-config"]["data"].get(os.path.basename(cfg), "{}"))
                check(tm.get("site") == "/etc/fleet/site.json", f"traffic-manager: {cfg} names site {tm.get('site')}, "
                      "not the ConfigMap's site.json")
            if name == "wms-adapter":
                check(env.get("FLEET_WMS_TLS") == "required", "wms-adapter: FLEET_WMS_TLS is not required")
            if name == "wms-adapter" and not postgres:
                # Event ids and webhook subscriptions survive a restart: the event log on a claim of its
                # own, one pod at a time (one writer).
                log = args[args.index("--events-log") + 1] if "--events-log" in args else ""
                m = mounts.get(os.path.dirname(log)) if log else None
                check(m is not None and not m.get("readOnly", False) and "persistentVolumeClaim" in vols[m["name"]],
                      f"wms-adapter: --events-log {log!r} is not on a writable PersistentVolumeClaim")
                check(spec.get("replicas") == 1 and spec.get("strategy", {}).get("type") == "Recreate",
                      "wms-adapter: with its event log on a claim, not one replica with strategy Recreate")
            if name == "wms-adapter":
                cfg = args[args.index("--config") + 1] if "--config" in args else ""
                h = json.loads(configmaps["fleet-config"]["data"].get(os.path.basename(cfg), "{}")).get("http", {})
                for key in ("tls_certificate", "tls_key"):
                    f = h.get(key, "")
                    check(f.startswith(DDS_DIR + "/") and f[len(DDS_DIR) + 1:] in items,
                          f"wms-adapter: http.{key} {f!r} is not an item of its {DDS_SECRET} mount")

    # The robot agents: one StatefulSet; pod robot-agent-N runs the robots of fleet-robots' agent-N.
    agents = statefulsets.get("robot-agent")
    robot_sets = {}
    site = json.loads(configmaps["fleet-config"]["data"]["site.json"])
    stations = {s["name"] for s in site["stations"]}
    if agents:
        spec = agents["spec"]
        replicas = spec.get("replicas", 1)
        c = spec["template"]["spec"]["containers"][0]
        check("--robot" not in c.get("args", []) and "--robots" not in c.get("args", []),
              "robot-agent: robots in the manifest's arguments, not from the ordinal")
        env = {e["name"]: e for e in c.get("env", [])}
        check(env.get("FLEET_POD_NAME", {}).get("valueFrom", {}).get("fieldRef", {}).get("fieldPath") == "metadata.name",
              "robot-agent: FLEET_POD_NAME is not the pod's name (downward API)")
        script = " ".join(c.get("command", []))
        check("FLEET_POD_NAME" in script and "/etc/fleet-robots/agent-" in script and "exec /usr/local/bin/robot_agent" in script,
              "robot-agent: the command does not pick the robots by the pod's ordinal")
        vols = {v["name"]: v for v in spec["template"]["spec"].get("volumes", [])}
        mounts = {m["mountPath"]: m["name"] for m in c.get("volumeMounts", [])}
        check(vols.get(mounts.get("/etc/fleet-robots"), {}).get("configMap", {}).get("name") == "fleet-robots",
              "robot-agent: ConfigMap fleet-robots not mounted at /etc/fleet-robots")
        check(spec.get("selector", {}).get("matchLabels", {}).items() <= spec["template"]["metadata"]["labels"].items(),
              "robot-agent: selector does not match its pods")
        svc = services.get(spec.get("serviceName", ""))
        check(svc is not None and svc["spec"].get("clusterIP") == "None",
              f"robot-agent: serviceName {spec.get('serviceName')} is not a headless Service (the pods' DNS names)")
        entries = configmaps.get("fleet-robots", {}).get("data", {})
        check(set(entries) == {f"agent-{i}" for i in range(replicas)},
              f"fleet-robots: entries {sorted(entries)} for {replicas} replicas (agent-0 .. agent-{replicas - 1})")
        seen = set()
        for key, text in entries.items():
            specs = text.split()
            check(specs, f"fleet-robots {key}: no robots")
            for r in specs:
                rid, _, station = r.partition("@")
                check(rid and station in stations, f"fleet-robots {key}: {r} is not ID@STATION with a station of site.json")
                check(rid not in seen, f"fleet-robots {key}: robot {rid} in two entries")
                seen.add(rid)
            robot_sets[key] = [r.split("@")[0] for r in specs]

    # The ops ports (no authentication) reachable only by monitoring pods and the nodes (kubelet probes).
    policies = by_kind.get("NetworkPolicy", {})
    ops_ports = {p["containerPort"] for d in workloads.values() for c in d["spec"]["template"]["spec"]["containers"]
                 for p in c.get("ports", []) if p["name"] == "ops"}
    guarded = set()
    for name, pol in policies.items():
        spec = pol["spec"]
        check("Ingress" in spec.get("policyTypes", []), f"NetworkPolicy {name}: no Ingress policy type")
        if spec.get("podSelector", {}).get("matchLabels", {}).items() <= {"app": "fleet"}.items():
            for rule in spec.get("ingress", []):
                ports = {p.get("port") for p in rule.get("ports", [])}
                if ports & ops_ports:
                    sources = rule.get("from", [])
                    check(sources and all("ipBlock" in f or f.get("podSelector", {}).get("matchLabels", {}).get(
                        "fleet.io/monitoring") == "true" for f in sources),
                          f"NetworkPolicy {name}: the ops ports open to more than monitoring pods and the nodes")
                    guarded |= ports & ops_ports
                elif not rule.get("ports") or any(p.get("port") is None and p.get("protocol", "TCP") == "TCP"
                                                  for p in rule["ports"]):
                    check(False, f"NetworkPolicy {name}: a rule admits every TCP port (the ops ports too)")
    check(guarded == ops_ports, f"no NetworkPolicy limits the ops ports {sorted(ops_ports - guarded)} to monitoring")

    # DDS peers: headless Services that select a workload's pods.
    dds = configmaps["fleet-config"]["data"]["cyclonedds.xml"]
    peers = re.findall(r'<Peer address="([^"]+)"', dds)
    check(len(peers) >= 5, f"only {len(peers)} DDS peers")
    check("<AllowMulticast>false</AllowMulticast>" in dds, "DDS multicast not off")
    # A headless Service's name resolves to one of its pods only: the pods of a StatefulSet on DDS
    # (the agents; on PostgreSQL the managers and adapters too) are named pod by pod
    # (<statefulset>-<ordinal>.<serviceName>, each pod's stable DNS name).
    on_dds = {n for n, w in workloads.items() for c in w["spec"]["template"]["spec"]["containers"]
              if "CYCLONEDDS_URI" in {e["name"] for e in c.get("env", [])}}
    pod_names = {f"{n}-{i}.{ss['spec'].get('serviceName')}": n for n, ss in statefulsets.items() if n in on_dds
                 for i in range(ss["spec"].get("replicas", 1))}
    for p in pod_names:
        check(p in peers, f"DDS peer {p} missing: that pod is found by no one")
        # The pods' names are records of their StatefulSet's headless Service: of the ready pods only
        # unless it publishes the others.
        s = services.get(p.split(".", 1)[1], {}).get("spec", {})
        check(s.get("clusterIP") == "None" and s.get("publishNotReadyAddresses") is True,
              f"DDS peer {p}: its Service is not headless or leaves pods that are not ready out of DNS "
              "(publishNotReadyAddresses)")
    for p in peers:
        if p in pod_names:
            continue
        s = services.get(p)
        check(s is not None and s["spec"].get("clusterIP") == "None", f"DDS peer {p} is not a headless Service or a pod's name")
        # A pod not ready yet (a standby manager, a manager waiting for its store) is still a DDS peer:
        # pods started after it must resolve it by the Service's name.
        check(s is None or s["spec"].get("publishNotReadyAddresses") is True,
              f"DDS peer {p}: the Service leaves pods that are not ready out of DNS (publishNotReadyAddresses)")
        if s:
            check(any(s["spec"]["selector"].items() <= d["spec"]["template"]["metadata"]["labels"].items()
                      for n, d in workloads.items() if n in on_dds), f"Service {p} selects no workload on DDS")
    check("traffic-manager-dds" in peers, "the traffic manager is no DDS peer")
    # Each JSON config parses; the site passes fleetctl's check.
    for key, text in configmaps["fleet-config"]["data"].items():
        if key.endswith(".json"):
            try:
                json.loads(text)
            except ValueError as e:
                check(False, f"ConfigMap {key}: {e}")
    with tempfile.TemporaryDirectory() as t:
        path = os.path.join(t, "site.json")
        open(path, "w").write(configmaps["fleet-config"]["data"]["site.json"])
        r = subprocess.run([fleetctl, "site", "check", path], capture_output=True, text=True, timeout=60)
        check(r.returncode == 0, f"site.json refused by fleetctl site check: {r.stdout}{r.stderr}")
    return by_kind, dds_items, robot_sets


def postgres_variant_checks(pg, base):
    """fleet.postgres.yaml beyond the rules of every manifest: the Secret fleet-postgres the only place
    of the password and the source of every URL; the database a StatefulSet with its claim from a
    volumeClaimTemplate; two managers and two adapters, each kept to one eviction at a time; PostgreSQL
    reachable from them only; and everything else as fleet.yaml has it (`base`)."""
    global current
    current = "deploy/kube/fleet.postgres.yaml"
    secret = pg.get("Secret", {}).get(PG_SECRET, {})
    values = {**secret.get("stringData", {}), **{k: base64.b64decode(v).decode() for k, v in secret.get("data", {}).items()}}
    check(set(values) == {"url", "password"}, f"Secret {PG_SECRET}: keys {sorted(values)}, not url and password")
    url = urllib.parse.urlsplit(values.get("url", ""))
    check(url.scheme == "postgresql" and url.hostname and url.password is None
          and "password" not in urllib.parse.parse_qs(url.query),
          f"Secret {PG_SECRET}: url {values.get('url')!r} is not a postgresql:// URL without a password")
    password = values.get("password", "")
    others = json.dumps([d for kind, docs in pg.items() for n, d in docs.items() if (kind, n) != ("Secret", PG_SECRET)])
    check(password and password not in others, f"the password of Secret {PG_SECRET} is written elsewhere in the file")
    # Every URL and password from the Secret: FLEET_STORE (managers), FLEET_EVENTS_LOG (adapters) its
    # url, PGPASSWORD (both) and FLEET_PG_PASSWORD (the database) its password; none in a literal.
    want = {"fleet-manager": {"FLEET_STORE": "url", "PGPASSWORD": "password"},
            "wms-adapter": {"FLEET_EVENTS_LOG": "url", "PGPASSWORD": "password"},
            "postgres": {"FLEET_PG_PASSWORD": "password"}}
    workloads = {**pg.get("Deployment", {}), **pg.get("StatefulSet", {})}
    for name, w in workloads.items():
        for c in w["spec"]["template"]["spec"]["containers"]:
            refs = {e["name"]: e.get("valueFrom", {}).get("secretKeyRef", {}) for e in c.get("env", [])}
            got = {n: r.get("key") for n, r in refs.items() if r.get("name") == PG_SECRET}
            check(got == want.get(name, {}), f"{name}: from Secret {PG_SECRET} {got}, not {want.get(name, {})}")
            literal = json.dumps([e.get("value") for e in c.get("env", [])] + c.get("args", []) + c.get("command", []))
            check("postgresql://" not in literal and not {"PGPASSWORD", "FLEET_PG_PASSWORD"} & {
                e["name"] for e in c.get("env", []) if "value" in e}, f"{name}: a database URL or password in a literal")
    # The database: one pod, its data on the claim of a volumeClaimTemplate, at the parent of the
    # data directory (initdb makes data/ 0700 as the user; a volume's root is not the user's).
    db = pg.get("StatefulSet", {}).get("postgres")
    check(db is not None, "no StatefulSet postgres")
    if db:
        spec = db["spec"]
        c = spec["template"]["spec"]["containers"][0]
        check(spec.get("replicas") == 1, "postgres: not one replica")
        claims = {t["metadata"]["name"]: t["spec"] for t in spec.get("volumeClaimTemplates", [])}
        mounts = {m["name"]: m for m in c.get("volumeMounts", [])}
        check(any("ReadWriteOnce" in s.get("accessModes", []) and s.get("resources", {}).get("requests", {}).get("storage")
                  and mounts.get(n, {}).get("mountPath") == "/var/lib/postgresql" and not mounts[n].get("readOnly")
                  for n, s in claims.items()),
              "postgres: no volumeClaimTemplate (ReadWriteOnce, a size) mounted writable at /var/lib/postgresql")
        check(not {v["name"] for v in spec["template"]["spec"].get("volumes", [])} & set(claims),
              "postgres: a pod volume hides the volumeClaimTemplate")
        sc = c.get("securityContext", {})
        check(sc.get("runAsNonRoot") is True and sc.get("runAsUser", 0) != 0 and sc.get("readOnlyRootFilesystem") is True
              and sc.get("allowPrivilegeEscalation") is False and sc.get("capabilities", {}).get("drop") == ["ALL"],
              "postgres: may run as root, write its root filesystem, escalate or keep capabilities")
        check(spec["template"]["spec"].get("securityContext", {}).get("fsGroup") == sc.get("runAsGroup"),
              "postgres: the claim not given to the database user's group (fsGroup)")
        check(any(m.get("mountPath") == "/tmp" for m in mounts.values()), "postgres: no writable /tmp (its socket)")
        res = c.get("resources", {})
        check({"cpu", "memory"} <= set(res.get("requests", {})) and {"cpu", "memory"} <= set(res.get("limits", {})),
              "postgres: requests/limits incomplete")
        check(c["image"] == f"localhost/fleet-postgres:{version}", f"postgres: image {c['image']}")
        for probe in ("livenessProbe", "readinessProbe"):
            check("pg_isready" in " ".join(c.get(probe, {}).get("exec", {}).get("command", [])),
                  f"postgres: {probe} is not pg_isready")
        live = c.get("livenessProbe", {})
        check(live.get("timeoutSeconds", 1) >= 10 and live.get("timeoutSeconds", 1) * live.get("failureThreshold", 3) >= 60,
              "postgres: livenessProbe restarts a merely busy pod")
        svc = pg.get("Service", {}).get(spec.get("serviceName", ""))
        check(svc is not None and svc["spec"]["selector"].items() <= spec["template"]["metadata"]["labels"].items()
              and url.hostname == svc["metadata"]["name"] and url.port in [p["port"] for p in svc["spec"]["ports"]],
              f"postgres: the url's {url.hostname}:{url.port} is not the Service {spec.get('serviceName')} of its pods")
    # Two managers, two adapters: a drain takes one at a time; PostgreSQL only from them.
    for name in ("fleet-manager", "wms-adapter"):
        check(workloads.get(name, {}).get("spec", {}).get("replicas") == 2, f"{name}: not two replicas")
        check(any(b["spec"].get("maxUnavailable") == 1 and b["spec"]["selector"]["matchLabels"].items()
                  <= workloads.get(name, {}).get("spec", {}).get("template", {}).get("metadata", {}).get("labels", {}).items()
                  for b in pg.get("PodDisruptionBudget", {}).values()),
              f"{name}: no PodDisruptionBudget of maxUnavailable 1")
    admitted = set()
    for pol in pg.get("NetworkPolicy", {}).values():
        if pol["spec"]["podSelector"].get("matchLabels", {}).get("service") == "postgres":
            for rule in pol["spec"].get("ingress", []):
                if 5432 in {p.get("port") for p in rule.get("ports", [])}:
                    for f in rule.get("from", [{}]):
                        exprs = f.get("podSelector", {}).get("matchExpressions", [])
                        admitted |= {v for e in exprs if e["key"] == "service" and e["operator"] == "In" for v in e["values"]}
                        if not exprs or set(f) != {"podSelector"}:
                            admitted.add("anyone")
    check(admitted == {"fleet-manager", "wms-adapter"}, f"PostgreSQL's port admits {sorted(admitted)}, not the "
          "managers and the adapters only")
    # Everything else as fleet.yaml: the same documents but for its claims and the two Deployments
    # that are StatefulSets here, whose pods differ only by the store and the URL.
    for kind, docs in base.items():
        for n, d in docs.items():
            if kind == "PersistentVolumeClaim" or (kind == "Deployment" and n in ("fleet-manager", "wms-adapter")):
                check(n not in pg.get(kind, {}), f"{kind} {n} of fleet.yaml kept")
                continue
            mine = pg.get(kind, {}).get(n)
            if kind == "ConfigMap" and n == "fleet-config" and mine:
                mine = {**mine, "data": {**mine["data"], **{k: d["data"][k] for k in ("manager.json", "cyclonedds.xml")}}}
            check(mine == d, f"{kind} {n} is not fleet.yaml's")
    for n, store in (("fleet-manager", "--db"), ("wms-adapter", "--events-log")):
        a, b = workloads.get(n), base.get("Deployment", {}).get(n)
        if not a or not b:
            continue
        pa, pb = copy.deepcopy(a["spec"]["template"]), copy.deepcopy(b["spec"]["template"])
        ca, cb = pa["spec"].pop("containers")[0], pb["spec"].pop("containers")[0]
        claim = [v["name"] for v in pb["spec"]["volumes"] if "persistentVolumeClaim" in v]
        pb["spec"]["volumes"] = [v for v in pb["spec"]["volumes"] if v["name"] not in claim]
        pa["spec"].pop("affinity", None)
        check(pa == pb, f"{n}: its pods' metadata and volumes are not fleet.yaml's (but the claim)")
        i = cb["args"].index(store)
        cb["args"][i:i + 2] = []
        cb["volumeMounts"] = [m for m in cb["volumeMounts"] if m["name"] not in claim]
        ca["env"] = [e for e in ca["env"] if e["name"] not in want[n]]
        for c in (ca, cb):
            c.pop("readinessProbe")
        check(ca == cb, f"{n}: its container is not fleet.yaml's but for the store, the URL and readiness")
    current = "deploy/kube/fleet.yaml"


pg_kinds = static_checks("fleet.postgres.yaml")[0]
# fleet.yaml last: the processes below run its workloads.
by_kind, dds_items, robot_sets = static_checks("fleet.yaml")
postgres_variant_checks(pg_kinds, by_kind)
configmaps = by_kind.get("ConfigMap", {})
secrets = by_kind.get("Secret", {})
services = by_kind.get("Service", {})
deployments = by_kind.get("Deployment", {})
statefulsets = by_kind.get("StatefulSet", {})
# The development variant: what scripts/kube-dev-variant makes of this file, no security in it.
r = subprocess.run([sys.executable, os.path.join(src, "scripts/kube-dev-variant"), "--check"], capture_output=True,
                   text=True, timeout=60)
check(r.returncode == 0, f"deploy/kube/fleet.dev.yaml: {r.stdout.strip()} {r.stderr.strip()[-300:]}")
dev_text = open(os.path.join(src, "deploy/kube/fleet.dev.yaml")).read()
dev_body = json.dumps([d for d in yaml.safe_load_all(dev_text) if d])  # without the comments
check(dev_text.startswith("# DEVELOPMENT ONLY") and DDS_SECRET not in dev_body and "required" not in dev_body
      and DDS_DIR not in dev_body, "deploy/kube/fleet.dev.yaml: not marked development-only, or security still in it")

def free_port():
    with socket.socket() as so:
        so.bind(("127.0.0.1", 0))
        return so.getsockname()[1]


def answer(port, path):
    try:
        with urllib.request.urlopen(f"http://127.0.0.1:{port}{path}", timeout=2) as r:
            return r.status
    except urllib.error.HTTPError as e:
        return e.code
    except OSError:
        return None


with tempfile.TemporaryDirectory() as t:
    etc, var, run = os.path.join(t, "etc"), os.path.join(t, "var"), os.path.join(t, "secrets")
    for d in (etc, var, run):
        os.makedirs(d)
    robots_dir = os.path.join(t, "robots")
    os.makedirs(robots_dir)
    # Each workload's mount of fleet-dds: its items of the Secret of the site made above.
    dds_root = os.path.join(t, "dds")
    for name, items in dds_items.items():
        for path, key in items.items():
            f = os.path.join(dds_root, name, path)
            os.makedirs(os.path.dirname(f), exist_ok=True)
            with open(os.open(f, os.O_WRONLY | os.O_CREAT, 0o400), "wb") as out:
                out.write(dds_files.get(key, b""))
    move = lambda text: (text.replace("/etc/fleet-robots", robots_dir).replace("/etc/fleet", etc)
                         .replace(DDS_DIR, os.path.join(dds_root, "wms-adapter"))
                         .replace("/var/lib/fleet", var).replace("/run/secrets/fleet", run)
                         .replace("/usr/local/bin/robot_agent", os.path.join(build, binaries["robot-agent"])))
    for key, text in configmaps["fleet-config"]["data"].items():
        open(os.path.join(etc, key), "w").write(move(text))
    for key, text in configmaps.get("fleet-robots", {}).get("data", {}).items():
        open(os.path.join(robots_dir, key), "w").write(text)
    for key, text in secrets["fleet-secrets"]["stringData"].items():
        open(os.path.join(run, key), "w").write(text)
    domain = str(210 + os.getpid() % 19)  # 210..228: away from the tests. 10..209
    procs = {}

    def start(name, workload, c, env, command):
        """One pod's container as a process: its env and arguments with the paths moved."""
        env = {e["name"]: e["value"] for e in c.get("env", []) if "value" in e} | env
        port = free_port()
        env.update(FLEET_METRICS_PORT=str(port), FLEET_METRICS_HOST="127.0.0.1", FLEET_DDS_DOMAIN=domain)
        # Loopback here (the cluster profile names the Services), with the pod's identity after it.
        mount = os.path.join(dds_root, workload)
        uri = env["CYCLONEDDS_URI"].split(",")
        env["CYCLONEDDS_URI"] = ",".join([f"file://{src}/deploy/cyclonedds-local.xml"] +
                                         [u.replace(DDS_DIR, mount) for u in uri[1:]])
        env["FLEET_DDS_SECURITY_DIR"] = mount
        log = open(os.path.join(t, f"{name}.log"), "w+")
        proc = subprocess.Popen(command + [move(a) for a in c.get("args", [])], env={**os.environ, **env},
                                stdout=log, stderr=subprocess.STDOUT, text=True)
        return proc, port, log

    try:
        for name, dep in deployments.items():
            c = dep["spec"]["template"]["spec"]["containers"][0]
            if name == "wms-adapter":  # the API port too: 8080 may be taken on this machine
                cfg = os.path.join(etc, "wms_adapter.json")
                j = json.load(open(cfg))
                api_port = free_port()
                j["http"].update(host="127.0.0.1", port=api_port)
                json.dump(j, open(cfg, "w"))
            procs[name] = start(name, name, c, {}, [os.path.join(build, binaries[name])])
        # The StatefulSet's pods: its command (the ordinal picks the robots) as a pod of that name runs it.
        for name, ss in statefulsets.items():
            c = ss["spec"]["template"]["spec"]["containers"][0]
            for i in range(ss["spec"].get("replicas", 1)):
                procs[f"{name}-{i}"] = start(f"{name}-{i}", name, c, {"FLEET_POD_NAME": f"{name}-{i}"},
                                             [move(a) for a in c["command"]])
        deadline = time.time() + 60  # a busy machine: DDS Security's handshakes take their time
        pending = {n: ("/readyz" if n in ("fleet-manager", "traffic-manager") else "/livez") for n in procs}
        while pending and time.time() < deadline:
            for n, path in list(pending.items()):
                if procs[n][0].poll() is not None:
                    procs[n][2].seek(0)
                    problems.append(f"{n} exited {procs[n][0].returncode} with the manifest's arguments: "
                                    f"{procs[n][2].read()[-400:]}")
                    del pending[n]
                elif answer(procs[n][1], path) == 200:
                    print(f"{n}: {path} 200 with the manifest's arguments and files")
                    del pending[n]
            time.sleep(0.2)
        for n, path in pending.items():
            problems.append(f"{n}: {path} not 200 within 60 s")
        # The API is https with the site's certificate (trusted through the site's CA), not plain http.
        if "wms-adapter" in procs and procs["wms-adapter"][0].poll() is None:
            ctx = ssl.create_default_context(cafile=os.path.join(site_dir, "ca.pem"))
            deadline = time.time() + 30  # the API port opens after the ops port: wait for it on a busy machine
            while True:
                try:
                    conn = httpclient.HTTPSConnection("localhost", api_port, context=ctx, timeout=5)
                    conn.request("GET", "/v1/health")
                    status = conn.getresponse().status
                    conn.close()
                    break
                except (OSError, ssl.SSLError) as e:
                    status = f"no answer: {e}"
                    if isinstance(e, ssl.SSLError) or time.time() > deadline:
                        break
                    time.sleep(0.2)
            check(status in (200, 503), f"wms-adapter: https://localhost:{api_port}/v1/health answered {status}")
            plain = answer(api_port, "/v1/health")
            check(plain is None, f"wms-adapter: plain http answered {plain}")
            print(f"wms-adapter: https with the site's certificate ({status}), plain http refused")
        # A pod whose ordinal has no entry (replicas raised without one) says so and exits 2.
        for name, ss in statefulsets.items():
            c = ss["spec"]["template"]["spec"]["containers"][0]
            extra = f"{name}-{ss['spec'].get('replicas', 1)}"
            proc, _, log = start(extra, name, c, {"FLEET_POD_NAME": extra}, [move(a) for a in c["command"]])
            try:
                proc.wait(timeout=20)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
            log.seek(0)
            out = log.read()
            check(proc.returncode == 2 and "has no robots" in out,
                  f"{extra} (no entry in fleet-robots) did not exit 2 naming the cause: exit {proc.returncode} {out[-300:]}")
            print(f"{extra}: exit {proc.returncode}: {out.strip()}")
    finally:
        for p, _, _ in procs.values():
            p.terminate()
        for p, _, _ in procs.values():
            try:
                p.wait(timeout=10)
            except subprocess.TimeoutExpired:
                p.kill()

    # Each agent pod drove its ordinal's robots (named in its start line; a single robot is a field
    # of its log lines, the last one written when it stops).
    for key, ids in sorted(robot_sets.items()):
        n = key.split("-")[-1]
        proc, port, log = procs.get(f"robot-agent-{n}", (None, None, None))
        if log is None:
            continue
        log.seek(0)
        text = log.read()
        check(f"robot agent robot-agent-{n}: {len(ids)} robots," in text,
              f"robot-agent-{n}: does not drive {len(ids)} robots as robot-agent-{n}: {text[-300:]}")
        if len(ids) == 1:
            check(f'"robot":"{ids[0]}"' in text, f"robot-agent-{n}: its log names no robot {ids[0]}: {text[-300:]}")
        print(f"robot-agent-{n}: drove {', '.join(ids)} (fleet-robots {key})")

for p in problems:
    print(p)
print(f"fleet.yaml: {len(deployments)} deployments, {len(statefulsets)} StatefulSets, {len(services)} services; "
      f"fleet.postgres.yaml: {len(pg_kinds.get('Deployment', {}))} deployments, {len(pg_kinds.get('StatefulSet', {}))} "
      f"StatefulSets, {len(pg_kinds.get('Service', {}))} services; checked, {len(problems)} problems")
sys.exit(1 if problems else 0)
