#!/usr/bin/env python3
"""Checks deploy/kube/fleet.yaml without a cluster (none runs here): every Deployment non-root with a
read-only root filesystem and no capabilities, requests and limits, liveness on /livez and readiness
on /readyz at the port the service serves them (FLEET_METRICS_PORT), images tagged with the project
version; the fleet manager one replica, strategy Recreate, its database on the PersistentVolumeClaim;
every ConfigMap, Secret, claim and config file referenced exists; a NetworkPolicy admits the ops
ports from monitoring pods and the nodes only, and liveness probes survive a busy node; every DDS peer is a headless
Service selecting a Deployment; the shipped site passes `fleetctl site check`. Then the closest to
running them that this machine offers: each Deployment's binary from BUILD_DIR started with the
manifest's arguments and the ConfigMap's and Secret's files (paths moved to a temporary folder, DDS
on loopback), which must come up live, and the fleet manager ready.
Usage: kube_manifests_check.py SOURCE_DIR BUILD_DIR"""
import json
import os
import re
import socket
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request

import yaml

src, build = sys.argv[1], sys.argv[2]
fleetctl = os.path.join(build, "services/fleetctl/fleetctl")
binaries = {"fleet-manager": "services/fleet_manager/fleet_manager", "wms-adapter": "services/wms_adapter/wms_adapter",
            "risk-map": "services/risk_map/risk_map", "robot-agent": "services/robot_agent/robot_agent"}
docs = [d for d in yaml.safe_load_all(open(os.path.join(src, "deploy/kube/fleet.yaml"))) if d]
version = re.search(r"project\(fleet VERSION ([0-9.]+)", open(os.path.join(src, "CMakeLists.txt")).read()).group(1)
problems = []


def check(cond, what):
    if not cond:
        problems.append(what)


by_kind = {}
for d in docs:
    by_kind.setdefault(d["kind"], {})[d["metadata"]["name"]] = d
configmaps = by_kind.get("ConfigMap", {})
secrets = by_kind.get("Secret", {})
claims = by_kind.get("PersistentVolumeClaim", {})
services = by_kind.get("Service", {})
deployments = by_kind.get("Deployment", {})
check(set(deployments) >= {"fleet-manager", "wms-adapter", "risk-map", "robot-agent"}, f"deployments: {sorted(deployments)}")

for name, dep in deployments.items():
    spec = dep["spec"]
    pod = spec["template"]["spec"]
    labels = spec["template"]["metadata"]["labels"]
    check(spec["selector"]["matchLabels"].items() <= labels.items(), f"{name}: selector does not match its pods")
    vols = {v["name"]: v for v in pod.get("volumes", [])}
    for v in vols.values():
        if "configMap" in v:
            check(v["configMap"]["name"] in configmaps, f"{name}: no ConfigMap {v['configMap']['name']}")
        if "secret" in v:
            check(v["secret"]["secretName"] in secrets, f"{name}: no Secret {v['secret']['secretName']}")
        if "persistentVolumeClaim" in v:
            check(v["persistentVolumeClaim"]["claimName"] in claims, f"{name}: no claim")
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
        check(str(ports.get("ops")) == env.get("FLEET_METRICS_PORT"), f"{where}: ops port != FLEET_METRICS_PORT")
        check(env.get("FLEET_METRICS_HOST") == "0.0.0.0", f"{where}: ops port only on loopback (the kubelet probes the pod IP)")
        for probe, path in (("livenessProbe", "/livez"), ("readinessProbe", "/readyz")):
            g = c.get(probe, {}).get("httpGet", {})
            check(g.get("path") == path and g.get("port") in ("ops", ports.get("ops")), f"{where}: {probe} not {path} on ops")
        live = c.get("livenessProbe", {})
        # A busy node answers late: a restart only after a minute of probes failing, each given 10 s.
        check(live.get("timeoutSeconds", 1) >= 10 and live.get("timeoutSeconds", 1) * live.get("failureThreshold", 3) >= 60,
              f"{where}: livenessProbe restarts a merely busy pod (timeoutSeconds x failureThreshold < 60 s)")
        mounts = {m["mountPath"]: m for m in c.get("volumeMounts", [])}
        for m in mounts.values():
            check(m["name"] in vols, f"{where}: mount of unknown volume {m['name']}")
        uri = env.get("CYCLONEDDS_URI", "")
        check(uri == "file:///etc/fleet/cyclonedds.xml" and "/etc/fleet" in mounts, f"{where}: DDS config not mounted")
        args = c.get("args", [])
        for flag in ("--config", "--site"):
            if flag in args:
                f = args[args.index(flag) + 1]
                check(f.startswith("/etc/fleet/") and os.path.basename(f) in configmaps["fleet-config"]["data"],
                      f"{where}: {flag} {f} not in the ConfigMap")
        if name == "fleet-manager":
            check(spec.get("replicas") == 1, "fleet-manager: more than one replica (one SQLite writer)")
            check(spec.get("strategy", {}).get("type") == "Recreate", "fleet-manager: not strategy Recreate")
            db = args[args.index("--db") + 1]
            m = mounts.get(os.path.dirname(db))
            check(m is not None and "persistentVolumeClaim" in vols[m["name"]], "fleet-manager: database not on the claim")

# The ops ports (no authentication) reachable only by monitoring pods and the nodes (kubelet probes).
policies = by_kind.get("NetworkPolicy", {})
ops_ports = {p["containerPort"] for d in deployments.values() for c in d["spec"]["template"]["spec"]["containers"]
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
                problems.append(f"NetworkPolicy {name}: a rule admits every TCP port (the ops ports too)")
check(guarded == ops_ports, f"no NetworkPolicy limits the ops ports {sorted(ops_ports - guarded)} to monitoring")

# DDS peers: headless Services that select a Deployment's pods.
dds = configmaps["fleet-config"]["data"]["cyclonedds.xml"]
peers = re.findall(r'<Peer address="([^"]+)"', dds)
check(len(peers) >= 4, f"only {len(peers)} DDS peers")
check("<AllowMulticast>false</AllowMulticast>" in dds, "DDS multicast not off")
for p in peers:
    s = services.get(p)
    check(s is not None and s["spec"].get("clusterIP") == "None", f"DDS peer {p} is not a headless Service")
    if s:
        check(any(s["spec"]["selector"].items() <= d["spec"]["template"]["metadata"]["labels"].items()
                  for d in deployments.values()), f"Service {p} selects no Deployment")
# Each JSON config parses; the site passes fleetctl's check.
for key, text in configmaps["fleet-config"]["data"].items():
    if key.endswith(".json"):
        try:
            json.loads(text)
        except ValueError as e:
            problems.append(f"ConfigMap {key}: {e}")
with tempfile.TemporaryDirectory() as t:
    path = os.path.join(t, "site.json")
    open(path, "w").write(configmaps["fleet-config"]["data"]["site.json"])
    r = subprocess.run([fleetctl, "site", "check", path], capture_output=True, text=True, timeout=60)
    check(r.returncode == 0, f"site.json refused by fleetctl site check: {r.stdout}{r.stderr}")



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
    move = lambda text: text.replace("/etc/fleet", etc).replace("/var/lib/fleet", var).replace("/run/secrets/fleet", run)
    for key, text in configmaps["fleet-config"]["data"].items():
        open(os.path.join(etc, key), "w").write(move(text))
    for key, text in secrets["fleet-secrets"]["stringData"].items():
        open(os.path.join(run, key), "w").write(text)
    domain = str(210 + os.getpid() % 19)  # 210..228: away from the tests. 10..209
    procs = {}
    try:
        for name, dep in deployments.items():
            c = dep["spec"]["template"]["spec"]["containers"][0]
            env = {e["name"]: e["value"] for e in c.get("env", [])}
            port = free_port()
            env.update(FLEET_METRICS_PORT=str(port), FLEET_METRICS_HOST="127.0.0.1", FLEET_DDS_DOMAIN=domain)
            env.pop("CYCLONEDDS_URI")  # loopback here; the cluster profile names the Services
            args = [move(a) for a in c.get("args", [])]
            if name == "wms-adapter":  # the API port too: 8080 may be taken on this machine
                cfg = os.path.join(etc, "wms_adapter.json")
                j = json.load(open(cfg))
                j["http"].update(host="127.0.0.1", port=free_port())
                json.dump(j, open(cfg, "w"))
            procs[name] = (subprocess.Popen([os.path.join(build, binaries[name])] + args, env={**os.environ, **env},
                                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True), port)
        deadline = time.time() + 30
        pending = {n: ("/readyz" if n == "fleet-manager" else "/livez") for n in procs}
        while pending and time.time() < deadline:
            for n, path in list(pending.items()):
                if procs[n][0].poll() is not None:
                    problems.append(f"{n} exited {procs[n][0].returncode} with the manifest's arguments: "
                                    f"{procs[n][0].stdout.read()[-400:]}")
                    del pending[n]
                elif answer(procs[n][1], path) == 200:
                    print(f"{n}: {path} 200 with the manifest's arguments and files")
                    del pending[n]
            time.sleep(0.2)
        for n, path in pending.items():
            problems.append(f"{n}: {path} not 200 within 30 s")
    finally:
        for p, _ in procs.values():
            p.terminate()
        for p, _ in procs.values():
            try:
                p.wait(timeout=10)
            except subprocess.TimeoutExpired:
                p.kill()

for p in problems:
    print("deploy/kube/fleet.yaml:", p)
print(f"{len(deployments)} deployments, {len(services)} services checked, {len(problems)} problems")
sys.exit(1 if problems else 0)
