#!/usr/bin/env python3
"""deploy/kube/fleet.yaml under `podman kube play`, the closest to a cluster that runs here, in its
secure default: DDS Security (each pod its identity of the Secret fleet-dds) and https on the API.

Each Deployment is played as its own pod on a DNS-enabled podman network made for this run, with the
name of the headless Service that selects it as the pod's network alias, so the DDS peers of the
ConfigMap's cyclonedds.xml resolve as in a cluster. podman 4.3 cannot play a StatefulSet: each of its
replicas is played as the Pod the StatefulSet controller would make (name <set>-<ordinal>, its
template, the aliases <set>-<ordinal>.<serviceName> and <serviceName>). The operator's step is done
here too: a site made by `scripts/dds-security site` (the adapter's certificate for wms-adapter) and
its Secret by `scripts/dds-security kube-secret`. What podman 4.3 (Debian 12)
needs beyond the manifest is done to a copy here and nowhere else: the Secret fleet-dds's volume is
a hostPath folder per pod holding that pod's items of the Secret, laid out by their paths as a
Secret volume lays them out (owned by the images' user, 0400; podman 4.3 would write each `data`
value as its base64 text and not apply `defaultMode`); the Secret's token (a placeholder
in the manifest) replaced by one of this run, in a form podman 4.3 writes into the file as sent; no
`ports` (podman 4.3 would publish each on the host's 0.0.0.0); every name prefixed with this run's
(pods, volumes and secrets are global in podman); and RES_OPTIONS=no-tld-query, so that a peer whose
pod is not up yet is looked up only in the network's own DNS, never on the host's resolvers. The
manifests have no simulator (robots bring their sensors); a simulator pod, added by this test, gives
the robot agents their sensors: the robots of the ConfigMap fleet-robots, at their stations.

Asserts: every pod and container runs; every service is live, and ready (the WMS adapter's readiness
needs the fleet manager over DDS between the pods); the API answers https with the site's
certificate (trusted through the site's CA, for the name wms-adapter) and not plain http; it refuses
a request without the Secret's token and accepts one with it; a container on the pods' network
without a certificate, writing Tasks onto the domain past the API, gets none to the fleet manager
(the check of compose_fleet_secure); a posted task is stored, assigned to one of fleet-robots' robots and
reaches `done` on the wall clock (DDS from adapter to manager to robot agent and back, the robot
driving the traffic manager's releases, which must have been sent); each agent pod drove its
ordinal's robots. Exit 77 (ctest skip) only when podman cannot run containers here.

With `postgres`: deploy/kube/fleet.postgres.yaml instead, played the same way (its StatefulSets
postgres, fleet-manager and wms-adapter expanded into their Pods as robot-agent's are, the claim of
postgres's volumeClaimTemplate made as the controller names it, pg-data-postgres-0). podman 4.3 reads
an env's secretKeyRef only from a podman secret holding JSON of base64 values, so the Secret
fleet-postgres is made so (its url as in the manifest, a password of this run for the placeholder),
not played. Asserts: postgres and every service live (the adapters, agents, risk map and traffic
manager ready), exactly one of the two managers active (its /readyz 200 and fleet_manager_active 1,
the other's 503 and 0); two tasks posted through the first adapter and acknowledged (201); the
active manager killed (podman kill --signal KILL of its container: kill -9); the other active
within 10 s (the time measured from the kill to its first /readyz 200, polled every 0.1 s, is
printed) with a newer lease epoch; the killed one started again (the kubelet's restart) stands by;
both tasks done, shown done by the second adapter, and both adapters give the same event ids for
the same transitions (GET /v1/events?since=0). The checks above of https, tokens and uncertified
writers are kube_play's own and not repeated.
Usage: kube_play.py SOURCE_DIR BUILD_DIR [postgres]"""
import base64
import copy
import functools
import http.client as httpclient
import json
import os
import re
import secrets
import shutil
import socket
import ssl
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request

import yaml

src, build = sys.argv[1], sys.argv[2]
postgres = sys.argv[3:] == ["postgres"]
if sys.argv[3:] and not postgres:
    sys.exit(__doc__.splitlines()[-1])
manifest = "deploy/kube/fleet.postgres.yaml" if postgres else "deploy/kube/fleet.yaml"
t0 = time.time()
run_id = f"fk{os.getpid()}"
token = secrets.token_hex(24)
pg_password = secrets.token_hex(16)
net = run_id


def podman(*args, check=True, timeout=120, stdin=None):
    r = subprocess.run(["podman", *args], capture_output=True, text=True, timeout=timeout, input=stdin)
    if check and r.returncode != 0:
        raise RuntimeError(f"podman {' '.join(args)}: {r.stderr.strip()[-600:]}")
    return r.stdout.strip()


def logs(container, lines):
    r = subprocess.run(["podman", "logs", "--tail", str(lines), container], capture_output=True, text=True)
    return (r.stdout + r.stderr).strip()


def fail(what):
    print("FAIL:", what)
    sys.exit(1)


if shutil.which("podman") is None:
    fail("podman is not installed (scripts/setup installs it)")
if subprocess.run(["podman", "info"], capture_output=True).returncode != 0:
    print("SKIP: podman cannot run here")
    sys.exit(77)
# Under ctest the fixture container_images built the images in this run (FLEET_IMAGES_BUILT=1).
if os.environ.get("FLEET_IMAGES_BUILT") != "1" and \
        subprocess.run([f"{src}/scripts/containers", "build"], env={**os.environ, "BUILD_DIR": build}).returncode != 0:
    fail("building the images failed")
r = subprocess.run(["podman", "run", "--rm", "--network", "none", "localhost/bookworm-min", "true"],
                   capture_output=True, text=True)
if r.returncode != 0:
    print("SKIP: podman cannot start a container here:", r.stderr.strip()[-300:])
    sys.exit(77)
print(f"images built after {time.time() - t0:.0f} s")
probe = os.path.join(build, "tests/integration/security/dds_probe")
if not os.access(probe, os.X_OK):
    fail(f"{probe} is not built")
DDS_SECRET, DDS_DIR, USER = "fleet-dds", "/run/fleet-dds", 65532
PG_SECRET = "fleet-postgres"


def remove_run(prefix):
    """Everything a run with this prefix made, also when it was killed before its own clean-up."""
    for what, rm in (("pod", ["pod", "rm", "-f", "-t", "1"]), ("volume", ["volume", "rm", "-f"]), ("secret", ["secret", "rm"])):
        names = [n for n in podman(what, "ls", "--format", "{{.Name}}", check=False).split() if n.startswith(prefix + "-")]
        if names:
            podman(*rm, *names, check=False)
    podman("network", "rm", "-f", prefix, check=False)


for old in podman("network", "ls", "--format", "{{.Name}}", check=False).split():
    m = re.fullmatch(r"fk(\d+)", old)
    if m and not os.path.exists(f"/proc/{m.group(1)}"):
        remove_run(old)

docs = [d for d in yaml.safe_load_all(open(f"{src}/{manifest}")) if d]
kinds = {}
for d in docs:
    kinds.setdefault(d["kind"], []).append(d)
deployments = kinds["Deployment"]
statefulsets = kinds.get("StatefulSet", [])
workloads = [d for d in docs if d["kind"] in ("Deployment", "StatefulSet")]  # manifest order
configmap = next(d for d in kinds["ConfigMap"] if d["metadata"]["name"] == "fleet-config")["data"]
robot_sets = next(d for d in kinds["ConfigMap"] if d["metadata"]["name"] == "fleet-robots")["data"]


def renamed(name):
    return f"{run_id}-{name}"


def part_for(dep):
    """The documents podman needs to play one Deployment or Pod, adapted as the docstring says."""
    out = []
    pod_spec = dep["spec"]["template"]["spec"] if dep["kind"] != "Pod" else dep["spec"]
    claims = {v["persistentVolumeClaim"]["claimName"] for v in pod_spec.get("volumes", [])
              if "persistentVolumeClaim" in v}
    # A claim in a second play would be made again: podman refuses an existing volume. The Secret
    # fleet-postgres is made as podman 4.3 reads an env's secretKeyRef (see the docstring).
    for d in kinds.get("ConfigMap", []) + [s for s in kinds.get("Secret", []) if s["metadata"]["name"] != PG_SECRET] + [
            c for c in kinds.get("PersistentVolumeClaim", []) if c["metadata"]["name"] in claims]:
        d = copy.deepcopy(d)
        d["metadata"]["name"] = renamed(d["metadata"]["name"])
        if d["kind"] == "Secret" and d["metadata"]["name"] == renamed("fleet-secrets"):
            # The operator's step (the manifest holds a placeholder): a token of this run. podman 4.3
            # reads `data` only and writes its base64 text into the file undecoded, so the token is
            # given as text that is valid base64 (hex), and the file holds it as sent.
            d.pop("stringData", None)
            d["data"] = {"wms-token": token}
        out.append(d)
    dep = copy.deepcopy(dep)
    dep["metadata"]["name"] = renamed(dep["metadata"]["name"])
    pod = dep["spec"]["template"]["spec"] if dep["kind"] != "Pod" else dep["spec"]
    for v in pod.get("volumes", []):
        if v.get("secret", {}).get("secretName") == DDS_SECRET:
            items = v.pop("secret").get("items")
            v["hostPath"] = {"path": dds_folder(dep["metadata"]["name"], items), "type": "Directory"}
            continue
        if "configMap" in v:
            v["configMap"]["name"] = renamed(v["configMap"]["name"])
        if "secret" in v:
            v["secret"]["secretName"] = renamed(v["secret"]["secretName"])
        if "persistentVolumeClaim" in v:
            v["persistentVolumeClaim"]["claimName"] = renamed(v["persistentVolumeClaim"]["claimName"])
    for c in pod["containers"]:
        for e in c.get("env", []):
            if "secretKeyRef" in e.get("valueFrom", {}):
                e["valueFrom"]["secretKeyRef"]["name"] = renamed(e["valueFrom"]["secretKeyRef"]["name"])
        c.setdefault("env", []).append({"name": "RES_OPTIONS", "value": "no-tld-query"})
        # podman 4.3 publishes every containerPort on the host's 0.0.0.0 (as if hostPort were set):
        # the two agent pods would collide on 9104, and nothing of a test may listen outside
        # loopback. The pods are reached at their own addresses; the probes keep their numbers.
        ports = {p["name"]: p["containerPort"] for p in c.pop("ports", []) if "name" in p}
        for probe in ("livenessProbe", "readinessProbe"):
            g = c.get(probe, {}).get("httpGet")
            if g and g.get("port") in ports:
                g["port"] = ports[g["port"]]
    return out + [dep]


def dds_folder(name, items):
    """The folder a Secret volume of fleet-dds with these items would be: each item's key of the
    site's Secret at its path, owned by the images' user, 0400 (every key when no items)."""
    folder = os.path.join(tmp, "dds-" + name)
    for item in items or [{"key": k, "path": k} for k in dds_data]:
        f = os.path.join(folder, item["path"])
        os.makedirs(os.path.dirname(f), exist_ok=True)
        with open(os.open(f, os.O_WRONLY | os.O_CREAT, 0o400), "wb") as out:
            out.write(base64.b64decode(dds_data[item["key"]]))
    for root, dirs, files in os.walk(folder):
        for n in dirs + files:
            os.chown(os.path.join(root, n), USER, USER)
    os.chmod(folder, 0o755)
    return folder


def aliases_of(dep):
    labels = dep["spec"]["template"]["metadata"]["labels"]
    return [s["metadata"]["name"] for s in kinds.get("Service", [])
            if s["spec"].get("clusterIP") == "None" and s["spec"]["selector"].items() <= labels.items()]


def pods_of(ss):
    """The Pods the StatefulSet controller makes: <name>-<ordinal>, with hostname and subdomain, and
    the claim <template>-<name>-<ordinal> of each volumeClaimTemplate."""
    out = []
    for i in range(ss["spec"].get("replicas", 1)):
        name = f"{ss['metadata']['name']}-{i}"
        spec = copy.deepcopy(ss["spec"]["template"]["spec"])
        spec.update(hostname=name, subdomain=ss["spec"]["serviceName"])
        for t in ss["spec"].get("volumeClaimTemplates", []):
            claim = copy.deepcopy(t)
            claim.update(apiVersion="v1", kind="PersistentVolumeClaim")
            claim["metadata"]["name"] = f"{t['metadata']['name']}-{name}"
            kinds.setdefault("PersistentVolumeClaim", []).append(claim)
            spec.setdefault("volumes", []).append({"name": t["metadata"]["name"],
                                                   "persistentVolumeClaim": {"claimName": claim["metadata"]["name"]}})
        out.append({"apiVersion": "v1", "kind": "Pod",
                    "metadata": {"name": name, "labels": ss["spec"]["template"]["metadata"]["labels"]}, "spec": spec})
    return out


# Requests to the pods' addresses only, never through a proxy of the environment.
direct = urllib.request.build_opener(urllib.request.ProxyHandler({}))


@functools.lru_cache(maxsize=None)
def pod_ip(pod):
    infra = podman("pod", "inspect", "--format", "{{.InfraContainerID}}", pod)
    return podman("inspect", "--format", f'{{{{(index .NetworkSettings.Networks "{net}").IPAddress}}}}', infra)


class SiteHttps(httpclient.HTTPSConnection):
    """https to a pod's address, the certificate checked against the site's CA for the name of the
    adapter's Service (wms-adapter), as a client in the cluster checks it."""

    def connect(self):
        sock = socket.create_connection((self.host, self.port), self.timeout)
        self.sock = self._context.wrap_socket(sock, server_hostname="wms-adapter")


def http(url, token=None, body=None):
    """(status, JSON body) of a request to https://ADDRESS:PORT/PATH; (None, None) without an answer."""
    hostport, path = url.split("://", 1)[1].split("/", 1)
    host, port = hostport.rsplit(":", 1)
    headers = {"Content-Type": "application/json"}
    if token:
        headers["Authorization"] = f"Bearer {token}"
    try:
        conn = SiteHttps(host, int(port), timeout=5, context=site_tls)
        conn.request("POST" if body is not None else "GET", "/" + path,
                     None if body is None else json.dumps(body), headers)
        r = conn.getresponse()
        text = r.read()
        conn.close()
        return r.status, json.loads(text or b"null") if r.status < 400 else None
    except (OSError, ssl.SSLError, httpclient.HTTPException, ValueError):
        return None, None


def plain_http(url):
    """The status of a plain-http GET; None when no http answer comes."""
    try:
        with direct.open(url, timeout=5) as r:
            return r.status
    except urllib.error.HTTPError as e:
        return e.code
    except (OSError, httpclient.HTTPException):
        return None


def ops_get(pod, port, path):
    """(status, text) of GET http://<pod's address>:<port><path>, a service's ops port on the run's
    network; (None, "") without an answer."""
    try:
        with direct.open(f"http://{pod_ip(pod)}:{port}{path}", timeout=5) as r:
            return r.status, r.read().decode()
    except urllib.error.HTTPError as e:
        return e.code, ""
    except (OSError, httpclient.HTTPException):
        return None, ""


def metric(text, name):
    return next((float(line.split()[1]) for line in text.splitlines() if line.startswith(name + " ")), None)


def events(base, last):
    """The events of GET <base>/v1/events?since=0 up to id `last` (each its data), read for at most 10 s."""
    host, port = base.split("://", 1)[1].rsplit(":", 1)
    out = []
    try:
        conn = SiteHttps(host, int(port), timeout=2, context=site_tls)
        conn.request("GET", "/v1/events?since=0", None, {"Authorization": f"Bearer {token}"})
        r = conn.getresponse()
        deadline = time.time() + 10
        while r.status == 200 and (not out or out[-1]["event_id"] < last) and time.time() < deadline:
            line = r.fp.readline()
            if not line:
                break
            if line.startswith(b"data:"):
                out.append(json.loads(line[5:]))
        conn.close()
    except (OSError, ssl.SSLError, httpclient.HTTPException, ValueError):
        pass
    return out


def standby_takeover():
    """The checks of the mode postgres (the docstring's)."""
    managers = [p for p, cs in pods if "fleet-manager" in cs]
    adapters = [p for p, cs in pods if "wms-adapter" in cs]
    if len(managers) != 2 or len(adapters) != 2:
        fail(f"not two managers and two adapters: {managers} {adapters}")
    c = next(w for w in workloads if w["metadata"]["name"] == "fleet-manager")["spec"]["template"]["spec"]["containers"][0]
    port = next(e["value"] for e in c["env"] if e["name"] == "FLEET_METRICS_PORT")
    # Exactly one active: it took the lease once the database answered.
    active, deadline = [], time.time() + 30
    while time.time() < deadline:
        active = [m for m in managers if ops_get(m, port, "/readyz")[0] == 200]
        if len(active) == 1:
            break
        time.sleep(0.2)
    if len(active) != 1:
        fail(f"{len(active)} of the two managers active (/readyz 200) after 30 s: {active}")
    first = active[0]
    other = next(m for m in managers if m != first)
    text = {m: ops_get(m, port, "/metrics")[1] for m in managers}
    if metric(text[first], "fleet_manager_active") != 1 or metric(text[other], "fleet_manager_active") != 0:
        fail(f"fleet_manager_active is not 1 on {first} and 0 on {other}")
    epoch = metric(text[first], "fleet_manager_lease_epoch")
    print(f"{first} active (lease epoch {epoch:.0f}), {other} standing by, after {time.time() - t0:.0f} s")

    # Two short tasks through the first adapter, acknowledged (201: stored by the active manager):
    # the robots at the first two parking places drive apart, one to the first charger (left of
    # them), the other two places along the row (right), so that neither waits for the other.
    base, base2 = (f"https://{pod_ip(a)}:8080" for a in adapters)
    stations = json.loads(configmap["site.json"])["stations"]
    parking = [s["name"] for s in stations if s["kind"] == "parking"]
    tasks = {"pg-0": next(s["name"] for s in stations if s["kind"] == "charging"), "pg-1": parking[len(robots) + 1]}
    for task, station in tasks.items():
        status, body = http(f"{base}/v1/tasks", token, {"id": task, "kind": "goto", "station": station})
        if status != 201:
            fail(f"POST /v1/tasks {task} answered {status} {body}")
    seen = {task: (http(f"{base}/v1/tasks/{task}", token)[1] or {}).get("state") for task in tasks}
    print(f"tasks acknowledged (201) by {adapters[0]}: {seen} after {time.time() - t0:.0f} s")

    # kill -9 of the active manager; the other must take over.
    podman("kill", "--signal", "KILL", f"{first}-fleet-manager")
    killed = time.time()
    while time.time() < killed + 10 and ops_get(other, port, "/readyz")[0] != 200:
        time.sleep(0.1)
    took = time.time() - killed
    if ops_get(other, port, "/readyz")[0] != 200:
        fail(f"{other} not active within 10 s of the kill -9 of {first}")
    text = ops_get(other, port, "/metrics")[1]
    if metric(text, "fleet_manager_active") != 1 or not (metric(text, "fleet_manager_lease_epoch") or 0) > epoch:
        fail(f"{other} answers /readyz but fleet_manager_active {metric(text, 'fleet_manager_active')}, "
             f"epoch {metric(text, 'fleet_manager_lease_epoch')} (before: {epoch:.0f})")
    seen = {task: (http(f"{base}/v1/tasks/{task}", token)[1] or {}).get("state") for task in tasks}
    print(f"killed {first} (-9): {other} active after {took:.1f} s, lease epoch "
          f"{metric(text, 'fleet_manager_lease_epoch'):.0f}; tasks {seen}")
    # The kubelet restarts a killed container; it must stand by. (podman stops a played pod whose
    # last container exited: started again, it has a new address, which a cluster's pod keeps.)
    podman("start", f"{first}-fleet-manager")
    pod_ip.cache_clear()

    deadline, states = time.time() + 120, {}
    while time.time() < deadline:
        states = {task: (http(f"{base}/v1/tasks/{task}", token)[1] or {}).get("state") for task in tasks}
        if all(s in ("done", "failed", "cancelled") for s in states.values()):
            break
        time.sleep(0.5)
    print(f"tasks {states} after {time.time() - t0:.0f} s, {time.time() - killed:.0f} s after the kill")
    if any(s != "done" for s in states.values()):
        fail(f"the tasks did not all reach done: {states}")

    # The second adapter: the same tasks done, the same events with the same ids (one log).
    deadline = time.time() + 10
    while time.time() < deadline:
        states2 = {task: (http(f"{base2}/v1/tasks/{task}", token)[1] or {}).get("state") for task in tasks}
        if all(s == "done" for s in states2.values()):
            break
        time.sleep(0.25)
    else:
        fail(f"{adapters[1]} does not show the tasks done: {states2}")
    last = (http(f"{base}/v1/webhooks", token)[1] or {}).get("last_event_id", 0)
    ours = [{k: e.get(k) for k in ("event_id", "id", "state", "seq")} for e in events(base, last)]
    theirs = [{k: e.get(k) for k in ("event_id", "id", "state", "seq")} for e in events(base2, last)]
    done_ids = {e["id"]: e["event_id"] for e in ours if e["state"] == "done"}
    if not ours or ours != theirs or set(done_ids) != set(tasks):
        fail(f"the adapters' events differ or lack the tasks' done: {ours} and {theirs}")
    print(f"{adapters[1]} shows the tasks done and the same {len(ours)} events, ids 1..{last} "
          f"(done: {done_ids})")

    # The killed manager, started again, stands by (live, /readyz 503, fleet_manager_active 0).
    deadline = time.time() + 20
    while time.time() < deadline:
        seen = (ops_get(first, port, "/livez")[0], ops_get(first, port, "/readyz")[0],
                metric(ops_get(first, port, "/metrics")[1], "fleet_manager_active"), ops_get(other, port, "/readyz")[0])
        if seen == (200, 503, 0, 200):
            break
        time.sleep(0.2)
    else:
        fail(f"{first}, started again, does not stand by with {other} active: its /livez, /readyz, "
             f"fleet_manager_active and the other's /readyz are {seen}")
    print(f"{first}, started again, stands by; {other} stays active")


tmp = tempfile.mkdtemp(prefix="fleet-kube-play.")
os.chmod(tmp, 0o755)
pods = []
readiness = {}
ok = False
rogue = None
try:
    # The operator's step: the site's files and its Secret fleet-dds.
    site = os.path.join(tmp, "site-dds")
    r = subprocess.run([f"{src}/scripts/dds-security", "site", site, "wms-adapter.fleet.svc"], capture_output=True,
                       text=True, timeout=120)
    if r.returncode != 0:
        fail(f"scripts/dds-security site: {r.stderr.strip()[-400:]}")
    r = subprocess.run([f"{src}/scripts/dds-security", "kube-secret", site], capture_output=True, text=True, timeout=60)
    if r.returncode != 0:
        fail(f"scripts/dds-security kube-secret: {r.stderr.strip()[-400:]}")
    dds_data = yaml.safe_load(r.stdout)["data"]
    site_tls = ssl.create_default_context(cafile=os.path.join(site, "ca.pem"))
    print(f"site CA, identities and the Secret {DDS_SECRET} ({len(dds_data)} keys) made after {time.time() - t0:.0f} s")
    podman("network", "create", net)
    if podman("network", "inspect", "--format", "{{.DNSEnabled}}", net) != "true":
        fail(f"network {net} has no DNS: the Services' names do not resolve (podman's CNI backend needs "
             "golang-github-containernetworking-plugin-dnsname; scripts/setup installs it)")
    def play(doc, aliases, pod):
        path = os.path.join(tmp, f"{doc['metadata']['name']}.yaml")
        yaml.safe_dump_all(part_for(doc), open(path, "w"))
        alias = ",".join(f"alias={a}" for a in aliases)
        podman("kube", "play", "--network", f"{net}:{alias}" if alias else net, path)
        spec = doc["spec"]["template"]["spec"] if doc["kind"] != "Pod" else doc["spec"]
        pods.append((pod, [c["name"] for c in spec["containers"]]))
        for c in spec["containers"]:  # its readinessProbe: a command, or a GET of its ops port
            probe = c.get("readinessProbe", {})
            get = probe.get("httpGet", {})
            port = {p["name"]: p["containerPort"] for p in c.get("ports", [])}.get(get.get("port"), get.get("port"))
            readiness[(pod, c["name"])] = probe["exec"]["command"] if "exec" in probe else (port, get.get("path"))

    if postgres:  # the operator's step: the Secret with the database's password
        pg = next(s for s in kinds["Secret"] if s["metadata"]["name"] == PG_SECRET)
        values = {**pg.get("stringData", {}), "password": pg_password}
        podman("secret", "create", renamed(PG_SECRET), "-",
               stdin=json.dumps({k: base64.b64encode(v.encode()).decode() for k, v in values.items()}))
    for w in workloads:  # manifest order: the database, then the fleet manager first
        if w["kind"] == "Deployment":
            play(w, aliases_of(w), renamed(w["metadata"]["name"]) + "-pod-0")
            continue
        for p in pods_of(w):
            play(p, aliases_of(w) + [f"{p['metadata']['name']}.{w['spec']['serviceName']}"],
                 renamed(p["metadata"]["name"]))
    print(f"{len(pods)} pods of {len(deployments)} Deployments and {len(statefulsets)} StatefulSets played "
          f"after {time.time() - t0:.0f} s")

    # The simulator, with the ConfigMap's site and the robots of fleet-robots at their stations.
    agent = next(ss for ss in statefulsets if ss["metadata"]["name"] == "robot-agent")
    robots = [{"id": r.split("@")[0], "start_station": r.split("@")[1]}
              for key in sorted(robot_sets) for r in robot_sets[key].split()]
    simdir = os.path.join(tmp, "sim")
    os.makedirs(simdir)
    for key in ("site.json", "cyclonedds.xml"):
        open(os.path.join(simdir, key), "w").write(configmap[key])
    json.dump({"name": "kube-play", "seed": 1, "dt": 0.1, "clock": "wall", "site": "site.json",
               "robots": robots, "humans": {"count": 0}}, open(os.path.join(simdir, "scenario.json"), "w"))
    sim_dds = dds_folder("sim", [{"key": k, "path": k.replace(".", "/", 1) if k.startswith("simulator.") else k}
                                 for k in ("ca.pem", "crl.pem", "governance.p7s", "simulator.security.xml",
                                           "simulator.cert.pem", "simulator.key.pem", "simulator.permissions.p7s")])
    image = agent["spec"]["template"]["spec"]["containers"][0]["image"].replace("fleet-robot-agent", "fleet-fleet-sim")
    sim = {"apiVersion": "v1", "kind": "Pod", "metadata": {"name": renamed("sim")},
           "spec": {"restartPolicy": "Never",
                    "volumes": [{"name": "sim", "hostPath": {"path": simdir, "type": "Directory"}},
                                {"name": "dds", "hostPath": {"path": sim_dds, "type": "Directory"}}],
                    "containers": [{"name": "fleet-sim", "image": image,
                                    "args": ["--scenario", "/etc/sim/scenario.json", "--clock", "wall",
                                             "--duration", "300", "--log-level", "info"],
                                    "env": [{"name": "CYCLONEDDS_URI", "value": "file:///etc/sim/cyclonedds.xml,"
                                             f"file://{DDS_DIR}/simulator/security.xml"},
                                            {"name": "FLEET_DDS_SECURITY_DIR", "value": DDS_DIR},
                                            {"name": "FLEET_DDS_DOMAIN", "value": "0"},
                                            {"name": "RES_OPTIONS", "value": "no-tld-query"}],
                                    "volumeMounts": [{"name": "sim", "mountPath": "/etc/sim", "readOnly": True},
                                                     {"name": "dds", "mountPath": DDS_DIR, "readOnly": True}]}]}}
    yaml.safe_dump(sim, open(os.path.join(tmp, "sim.yaml"), "w"))
    podman("kube", "play", "--network", net, os.path.join(tmp, "sim.yaml"))
    pods.append((renamed("sim"), ["fleet-sim"]))

    for pod, containers in pods:
        for c in containers:
            state = podman("inspect", "--format", "{{.State.Status}}", f"{pod}-{c}", check=False)
            if state != "running":
                fail(f"{pod}-{c} is {state or 'missing'}: {logs(f'{pod}-{c}', 5)}")

    # Live and ready (the adapter is ready once it hears the manager; the agent once it has sensors;
    # /readyz answers 200 only when live too): each container as its readinessProbe says, a GET of
    # its ops port at the pod's address, as the kubelet sends it, or its command.
    pending = {f"{pod}-{c}": (pod, readiness[(pod, c)]) for pod, cs in pods[:-1] for c in cs}
    deadline = time.time() + 60
    while pending and time.time() < deadline:
        for c, (pod, how) in list(pending.items()):
            if isinstance(how, tuple):
                passed = ops_get(pod, *how)[0] == 200
            else:
                passed = subprocess.run(["podman", "exec", c, *how], capture_output=True).returncode == 0
            if passed:
                del pending[c]
        time.sleep(0.2)
    if pending:
        fail(f"not live or not ready after 60 s: {sorted(pending)}")
    print(f"every service live and ready after {time.time() - t0:.0f} s")
    if postgres:
        standby_takeover()
        ok = True
        print(f"PASS: podman kube play of {manifest}: a kill -9 of the active fleet manager taken over, the tasks done "
              f"and the same event ids on both WMS adapters, in {time.time() - t0:.0f} s")
        sys.exit(0)  # the clean-up below runs

    adapter = next(p for p, cs in pods if "wms-adapter" in cs)
    base = f"https://{pod_ip(adapter)}:8080"
    status, _ = http(f"{base}/v1/health")
    if status not in (200, 503):
        fail(f"GET {base}/v1/health with the site's CA answered {status}")
    plain = plain_http(base.replace("https://", "http://") + "/v1/health")
    if plain is not None:
        fail(f"the API answered plain http ({plain}): not https only")
    print(f"the API answers https with the site's certificate for wms-adapter ({status}), not plain http")
    stored = subprocess.run(["podman", "exec", f"{adapter}-wms-adapter", "cat", "/run/secrets/fleet/wms-token"],
                            capture_output=True, text=True).stdout
    if stored != token:
        fail(f"the Secret's token file holds {stored!r}, not the token of this run")
    status, _ = http(f"{base}/v1/tasks")
    if status != 401:
        fail(f"GET /v1/tasks without the Secret's token answered {status}, not 401")
    site = json.loads(configmap["site.json"])
    pickup = next(s["name"] for s in site["stations"] if s["kind"] == "pickup")
    dropoff = next(s["name"] for s in site["stations"] if s["kind"] == "dropoff")
    status, body = http(f"{base}/v1/tasks", token, {"id": "kube-1", "kind": "transport", "pickup": pickup,
                                                    "dropoff": dropoff, "load_duration_ns": 1000000000,
                                                    "unload_duration_ns": 1000000000})
    if status != 201:
        fail(f"POST /v1/tasks with the Secret's token answered {status} {body}")
    # Meanwhile a container on the pods' network without a certificate writes Tasks rogue-<n> onto
    # the domain (the ConfigMap's DDS profile, no identity): none may reach the manager.
    rogue = subprocess.Popen(["podman", "run", "--rm", "--name", renamed("rogue"), "--network", net, "--user", str(USER),
                              "-e", "FLEET_DDS_DOMAIN=0", "-e", "RES_OPTIONS=no-tld-query",
                              "-e", "CYCLONEDDS_URI=file:///etc/sim/cyclonedds.xml", "-v", f"{simdir}:/etc/sim:ro",
                              "-v", f"{probe}:/usr/local/bin/dds_probe:ro", "--entrypoint", "/usr/local/bin/dds_probe",
                              image.replace("fleet-fleet-sim", "fleet-fleet-manager"), "write", "4", "rogue"],
                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    # The wall clock, as deployed: the robot drives some 45 m (about 60 s).
    robot, state, seen = None, None, []
    deadline = time.time() + 180
    while time.time() < deadline:
        status, view = http(f"{base}/v1/tasks/kube-1", token)
        if status == 200:
            robot, state = view.get("robot") or robot, view.get("state")  # a done task names no robot
            if not seen or seen[-1] != state:
                seen.append(state)
            if state in ("done", "failed", "cancelled"):
                break
        time.sleep(1)
    print(f"task kube-1: {' -> '.join(map(str, seen))} by {robot} after {time.time() - t0:.0f} s")
    if state != "done" or robot not in [r["id"] for r in robots]:
        fail(f"the task did not reach done with a robot of fleet-robots (state {state}, robot {robot})")
    out = [line for line in rogue.communicate(timeout=60)[0].strip().splitlines() if not line.startswith("time=")]
    if rogue.returncode not in (0, 3, 4):  # dds_probe's: ran, writer refused, participant refused
        fail(f"the uncertified container did not run (exit {rogue.returncode}): {out[-3:]}")
    status, _ = http(f"{base}/v1/tasks/rogue-0", token)
    if status != 404:
        fail(f"a Task written by a container without a certificate reached the manager (GET rogue-0: {status})")
    print(f"uncertified container: exit {rogue.returncode} {out[-1] if out else ''}; no Task of it reached the manager")
    traffic = next(p for p, cs in pods if "traffic-manager" in cs)
    metrics = podman("exec", f"{traffic}-traffic-manager", "/usr/local/bin/fleet-probe", "/metrics")
    releases = next((float(line.split()[1]) for line in metrics.splitlines()
                     if line.startswith("traffic_manager_releases_total ")), 0)
    if releases < 1:
        fail("the traffic manager sent no releases")
    print(f"the traffic manager sent {releases:.0f} releases")

    # Each agent pod drove its ordinal's robots (a single robot is a field of its log lines, of its
    # statistics every 10 s).
    for key in sorted(robot_sets):
        ids = [r.split("@")[0] for r in robot_sets[key].split()]
        c = f"{renamed(agent['metadata']['name'])}-{key.split('-')[-1]}-robot-agent"
        text = logs(c, 1000)
        if f": {len(ids)} robots," not in text or (len(ids) == 1 and f'"robot":"{ids[0]}"' not in text):
            fail(f"{c} does not drive {', '.join(ids)} (fleet-robots {key}): {text[-300:]}")
        print(f"{c}: drives {', '.join(ids)}")
    ok = True
    print(f"PASS: podman kube play of deploy/kube/fleet.yaml, DDS Security and https on (the secure default), "
          f"in {time.time() - t0:.0f} s")
finally:
    if not ok:
        for pod, containers in pods:
            for c in containers:
                print(f"--- log of {pod}-{c}")
                print(logs(f"{pod}-{c}", 15))
    if rogue is not None and rogue.poll() is None:
        podman("rm", "-f", "-t", "1", renamed("rogue"), check=False)
        rogue.wait()
    remove_run(run_id)
    shutil.rmtree(tmp, ignore_errors=True)
