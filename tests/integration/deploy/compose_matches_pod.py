#!/usr/bin/env python3
"""deploy/compose.yaml cannot be run here (no docker; Debian's podman-compose 1.0.3 cannot express
network_mode, docs/operator-guide.md#compose), so this checks that it describes the same fleet as
deploy/fleet-pod.yaml, which containers_smoke runs in CI: per service the same image, entrypoint and
arguments, environment, mounts and health check, and the network namespace shared with a manager
that has no network. Usage: compose_matches_pod.py SOURCE_DIR"""
import sys

import yaml

src = sys.argv[1]
compose = yaml.safe_load(open(f"{src}/deploy/compose.yaml"))["services"]
pod = {c["name"]: c for c in yaml.safe_load(open(f"{src}/deploy/fleet-pod.yaml"))["spec"]["containers"]}
problems = []


def check(cond, what):
    if not cond:
        problems.append(what)


check(set(pod) <= set(compose), f"services missing in compose.yaml: {sorted(set(pod) - set(compose))}")
for name, c in pod.items():
    s = compose.get(name)
    if s is None:
        continue
    check(s.get("image") == c["image"], f"{name}: image {s.get('image')} != pod's {c['image']}")
    # The pod's arguments with the run's duration filled in as compose has it.
    args = [a.replace("__DURATION__", "180") for a in c.get("args", [])]
    check(s.get("command") == args, f"{name}: command {s.get('command')} != pod's args {args}")
    entry = [a.replace('"$@"', '"$$@"') for a in c.get("command", [])] or None
    check(s.get("entrypoint") == entry, f"{name}: entrypoint {s.get('entrypoint')} != pod's command {entry}")
    env = {e["name"]: e["value"] for e in c.get("env", [])}
    check(all(s.get("environment", {}).get(k) == v for k, v in env.items()),
          f"{name}: environment {s.get('environment')} lacks the pod's {env}")
    mounts = {m["mountPath"]: m.get("readOnly", False) for m in c.get("volumeMounts", [])}
    # host:container[:ro], where the host part may itself hold ':' (${VAR:?message}).
    vols = {(v[:-3] if v.endswith(":ro") else v).rsplit(":", 1)[1]: v.endswith(":ro") for v in s.get("volumes", [])}
    check(all(p in vols and vols[p] == ro for p, ro in mounts.items()),
          f"{name}: volumes {s.get('volumes')} do not mount {mounts}")
    probe = c.get("livenessProbe", {}).get("exec", {}).get("command")
    if probe:
        check(s.get("healthcheck", {}).get("test") == ["CMD"] + probe,
              f"{name}: healthcheck {s.get('healthcheck')} != pod's probe {probe}")
    http = c.get("livenessProbe", {}).get("httpGet")
    if http:
        check("healthcheck" in s and str(http["port"]) in " ".join(s["healthcheck"]["test"]),
              f"{name}: no health check on port {http['port']}")
    # One private loopback for the whole fleet, as in the --network none pod.
    expected = "none" if name == "fleet-manager" else "service:fleet-manager"
    check(s.get("network_mode") == expected, f"{name}: network_mode {s.get('network_mode')} != {expected}")

for p in problems:
    print("compose.yaml:", p)
print(f"{len(pod)} services compared, {len(problems)} problems")
sys.exit(1 if problems else 0)
