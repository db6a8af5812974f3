#!/usr/bin/env python3
"""deploy/kube/fleet.yaml under `podman kube play`, the closest to a cluster that runs here.

Each Deployment is played as its own pod on a DNS-enabled podman network made for this run, with the
name of the headless Service that selects it as the pod's network alias, so the DDS peers of the
ConfigMap's cyclonedds.xml resolve as in a cluster. podman 4.3 cannot play a StatefulSet: each of its
replicas is played as the Pod the StatefulSet controller would make (name <set>-<ordinal>, its
template, the aliases <set>-<ordinal>.<serviceName> and <serviceName>). What podman 4.3 (Debian 12)
needs beyond the manifest is done to a copy here and nowhere else: the Secret's token (a placeholder
in the manifest) replaced by one of this run, in a form podman 4.3 writes into the file as sent; no
`ports` (podman 4.3 would publish each on the host's 0.0.0.0); every name prefixed with this run's
(pods, volumes and secrets are global in podman); and RES_OPTIONS=no-tld-query, so that a peer whose
pod is not up yet is looked up only in the network's own DNS, never on the host's resolvers. The
manifests have no simulator (robots bring their sensors); a simulator pod, added by this test, gives
the robot agents their sensors: the robots of the ConfigMap fleet-robots, at their stations.

Asserts: every pod and container runs; every service is live, and ready (the WMS adapter's readiness
needs the fleet manager over DDS between the pods); the API refuses a request without the Secret's
token and accepts one with it; a posted task is stored, assigned to one of fleet-robots' robots and
reaches `done` on the wall clock (DDS from adapter to manager to robot agent and back, the robot
driving the traffic manager's releases, which must have been sent); each agent pod drove its
ordinal's robots. Exit 77 (ctest skip) only when podman cannot run containers here.
Usage: kube_play.py SOURCE_DIR BUILD_DIR"""
import copy
import json
import os
import re
import secrets
import shutil
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request

import yaml

src, build = sys.argv[1], sys.argv[2]
t0 = time.time()
run_id = f"fk{os.getpid()}"
token = secrets.token_hex(24)
net = run_id


def podman(*args, check=True, timeout=120):
    r = subprocess.run(["podman", *args], capture_output=True, text=True, timeout=timeout)
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
if subprocess.run([f"{src}/scripts/containers", "build"], env={**os.environ, "BUILD_DIR": build}).returncode != 0:
    fail("building the images failed")
r = subprocess.run(["podman", "run", "--rm", "--network", "none", "localhost/bookworm-min", "true"],
                   capture_output=True, text=True)
if r.returncode != 0:
    print("SKIP: podman cannot start a container here:", r.stderr.strip()[-300:])
    sys.exit(77)
print(f"images built after {time.time() - t0:.0f} s")


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

docs = [d for d in yaml.safe_load_all(open(f"{src}/deploy/kube/fleet.yaml")) if d]
kinds = {}
for d in docs:
    kinds.setdefault(d["kind"], []).append(d)
deployments = kinds["Deployment"]
statefulsets = kinds.get("StatefulSet", [])
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
    # A claim in a second play would be made again: podman refuses an existing volume.
    for d in kinds.get("ConfigMap", []) + kinds.get("Secret", []) + [
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
        if "configMap" in v:
            v["configMap"]["name"] = renamed(v["configMap"]["name"])
        if "secret" in v:
            v["secret"]["secretName"] = renamed(v["secret"]["secretName"])
        if "persistentVolumeClaim" in v:
            v["persistentVolumeClaim"]["claimName"] = renamed(v["persistentVolumeClaim"]["claimName"])
    for c in pod["containers"]:
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


def aliases_of(dep):
    labels = dep["spec"]["template"]["metadata"]["labels"]
    return [s["metadata"]["name"] for s in kinds.get("Service", [])
            if s["spec"].get("clusterIP") == "None" and s["spec"]["selector"].items() <= labels.items()]


def pods_of(ss):
    """The Pods the StatefulSet controller makes: <name>-<ordinal>, with hostname and subdomain."""
    out = []
    for i in range(ss["spec"].get("replicas", 1)):
        name = f"{ss['metadata']['name']}-{i}"
        spec = copy.deepcopy(ss["spec"]["template"]["spec"])
        spec.update(hostname=name, subdomain=ss["spec"]["serviceName"])
        out.append({"apiVersion": "v1", "kind": "Pod",
                    "metadata": {"name": name, "labels": ss["spec"]["template"]["metadata"]["labels"]}, "spec": spec})
    return out


def pod_ip(pod):
    infra = podman("pod", "inspect", "--format", "{{.InfraContainerID}}", pod)
    return podman("inspect", "--format", f'{{{{(index .NetworkSettings.Networks "{net}").IPAddress}}}}', infra)


def http(url, token=None, body=None):
    req = urllib.request.Request(url, data=None if body is None else json.dumps(body).encode(),
                                 headers={"Content-Type": "application/json"})
    if token:
        req.add_header("Authorization", f"Bearer {token}")
    try:
        with urllib.request.urlopen(req, timeout=5) as r:
            return r.status, json.loads(r.read() or b"null")
    except urllib.error.HTTPError as e:
        return e.code, None
    except OSError:
        return None, None


tmp = tempfile.mkdtemp(prefix="fleet-kube-play.")
pods = []
ok = False
try:
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

    for dep in deployments:  # manifest order: the fleet manager first
        play(dep, aliases_of(dep), renamed(dep["metadata"]["name"]) + "-pod-0")
    for ss in statefulsets:
        for p in pods_of(ss):
            play(p, aliases_of(ss) + [f"{p['metadata']['name']}.{ss['spec']['serviceName']}"],
                 renamed(p["metadata"]["name"]))
    print(f"{len(pods)} pods of {len(deployments)} Deployments and {len(statefulsets)} StatefulSets played "
          f"after {time.time() - t0:.0f} s")

    # The simulator, with the ConfigMap's site and the robots of fleet-robots at their stations.
    agent = statefulsets[0]
    robots = [{"id": r.split("@")[0], "start_station": r.split("@")[1]}
              for key in sorted(robot_sets) for r in robot_sets[key].split()]
    simdir = os.path.join(tmp, "sim")
    os.makedirs(simdir)
    for key in ("site.json", "cyclonedds.xml"):
        open(os.path.join(simdir, key), "w").write(configmap[key])
    json.dump({"name": "kube-play", "seed": 1, "dt": 0.1, "clock": "wall", "site": "site.json",
               "robots": robots, "humans": {"count": 0}}, open(os.path.join(simdir, "scenario.json"), "w"))
    os.chmod(tmp, 0o755)
    image = agent["spec"]["template"]["spec"]["containers"][0]["image"].replace("fleet-robot-agent", "fleet-fleet-sim")
    sim = {"apiVersion": "v1", "kind": "Pod", "metadata": {"name": renamed("sim")},
           "spec": {"restartPolicy": "Never",
                    "volumes": [{"name": "sim", "hostPath": {"path": simdir, "type": "Directory"}}],
                    "containers": [{"name": "fleet-sim", "image": image,
                                    "args": ["--scenario", "/etc/sim/scenario.json", "--clock", "wall",
                                             "--duration", "300", "--log-level", "info"],
                                    "env": [{"name": "CYCLONEDDS_URI", "value": "file:///etc/sim/cyclonedds.xml"},
                                            {"name": "FLEET_DDS_DOMAIN", "value": "0"},
                                            {"name": "RES_OPTIONS", "value": "no-tld-query"}],
                                    "volumeMounts": [{"name": "sim", "mountPath": "/etc/sim", "readOnly": True}]}]}}
    yaml.safe_dump(sim, open(os.path.join(tmp, "sim.yaml"), "w"))
    podman("kube", "play", "--network", net, os.path.join(tmp, "sim.yaml"))
    pods.append((renamed("sim"), ["fleet-sim"]))

    for pod, containers in pods:
        for c in containers:
            state = podman("inspect", "--format", "{{.State.Status}}", f"{pod}-{c}", check=False)
            if state != "running":
                fail(f"{pod}-{c} is {state or 'missing'}: {logs(f'{pod}-{c}', 5)}")

    # Live and ready (the adapter is ready once it hears the manager; the agent once it has sensors).
    pending = {f"{pod}-{c}": path for pod, cs in pods[:-1] for c in cs for path in ("/livez", "/readyz")}
    deadline = time.time() + 60
    while pending and time.time() < deadline:
        for c, path in list(pending.items()):
            r = subprocess.run(["podman", "exec", c, "/usr/local/bin/fleet-probe", path], capture_output=True, text=True)
            if r.returncode == 0:
                del pending[c]
        time.sleep(0.5)
    if pending:
        fail(f"not live or not ready after 60 s: {pending}")
    print(f"every service live and ready after {time.time() - t0:.0f} s")

    adapter = next(p for p, cs in pods if "wms-adapter" in cs)
    base = f"http://{pod_ip(adapter)}:8080"
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
    print(f"PASS: podman kube play of deploy/kube/fleet.yaml in {time.time() - t0:.0f} s")
finally:
    if not ok:
        for pod, containers in pods:
            for c in containers:
                print(f"--- log of {pod}-{c}")
                print(logs(f"{pod}-{c}", 15))
    remove_run(run_id)
    shutil.rmtree(tmp, ignore_errors=True)
