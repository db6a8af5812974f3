#!/usr/bin/env python3
"""Checks, without podman, that deploy/compose.yaml describes the same fleet as deploy/fleet-pod.yaml
(which containers_smoke runs) and that its network settings hang together; compose_fleet runs it.
Per service: the same image, entrypoint and arguments (the adapter reads its stations from the
wms_adapter.json that scripts/containers writes, which must name the pod's stations and listen on
all addresses of its container), environment, mounts, health check, read-only root filesystem and
no privilege escalation; the adapter's event log (--events-log or FLEET_EVENTS_LOG) on the writable data mount. Network: every service on the project network `fleet`, none in another's
namespace; the compose DDS profile (in the images) with multicast off and exactly the DDS services'
names as unicast peers; only the adapter publishes a port, on 127.0.0.1. Secure by default: each
DDS service of compose.yaml, compose.vda5050.yaml and the Pod requires DDS Security and joins with
its own identity from /etc/fleet/dds, the adapter requires https; the dev overlays
(compose.dev.yaml, compose.dev.vda5050.yaml, fleet-pod.dev.yaml) turn both off for every one of
them and for nothing else. Usage: compose_matches_pod.py SOURCE_DIR"""
import json
import os
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

import yaml

src = sys.argv[1]
doc = yaml.safe_load(open(f"{src}/deploy/compose.yaml"))
compose = doc["services"]
# The overlay's new services (MQTT broker, VDA 5050 bridge) join the same network
# under the same rules; the services it only adds settings to are compose.yaml's.
overlay = yaml.safe_load(open(f"{src}/deploy/compose.vda5050.yaml"))["services"]
added = {n: s for n, s in overlay.items() if n not in compose}
# The PostgreSQL overlay's second manager and second adapter: DDS services under the same rules;
# its database is not one.
pg_overlay = yaml.safe_load(open(f"{src}/deploy/compose.postgres.yaml"))["services"]
added.update({n: s for n, s in pg_overlay.items() if n not in compose and n != "postgres"})
NOT_DDS = ("fleetctl", "mosquitto")
pod = {c["name"]: c for c in yaml.safe_load(open(f"{src}/deploy/fleet-pod.yaml"))["spec"]["containers"]}
problems = []
PROFILE = "cyclonedds-compose.xml"


def check(cond, what):
    if not cond:
        problems.append(what)


with tempfile.TemporaryDirectory() as t:
    subprocess.run([f"{src}/scripts/containers", "files", t], check=True, stdout=subprocess.DEVNULL)
    adapter_cfg = json.load(open(f"{t}/config/wms_adapter.json"))

check(set(pod) <= set(compose), f"services missing in compose.yaml: {sorted(set(pod) - set(compose))}")
# Every robot agent drives only what the traffic manager releases: both files run one.
check("traffic-manager" in pod and "traffic-manager" in compose, "no traffic-manager in the pod or compose.yaml")
check("traffic-manager" not in overlay, "compose.vda5050.yaml redefines compose.yaml's traffic-manager")
for name, c in pod.items():
    s = compose.get(name)
    if s is None:
        continue
    check(s.get("image") == c["image"], f"{name}: image {s.get('image')} != pod's {c['image']}")
    # The pod's arguments with the run's duration as compose fills it in.
    args = [a.replace("__DURATION__", "${FLEET_SIM_SECONDS:-180}") for a in c.get("args", [])]
    if name == "wms-adapter" and "--stations" in args:
        i = args.index("--stations")
        check(adapter_cfg.get("stations") == args[i + 1],
              f"wms_adapter.json names stations {adapter_cfg.get('stations')}, the pod {args[i + 1]}")
        check(adapter_cfg.get("http", {}).get("host") == "0.0.0.0",
              "wms_adapter.json: http.host must be 0.0.0.0, or the published port reaches nothing")
        args[i:i + 2] = ["--config", "/etc/fleet/wms_adapter.json"]
    check(s.get("command") == args, f"{name}: command {s.get('command')} != pod's args {args}")
    if name == "wms-adapter":
        # Event ids and webhook subscriptions survive a restart: the event log on the writable data
        # mount in both.
        penv = {e["name"]: e["value"] for e in c.get("env", [])}
        log = args[args.index("--events-log") + 1] if "--events-log" in args else penv.get("FLEET_EVENTS_LOG", "")
        writable = [m["mountPath"] for m in c.get("volumeMounts", []) if not m.get("readOnly", False)]
        check(log.startswith("/var/lib/fleet/") and "/var/lib/fleet" in writable,
              f"wms-adapter: --events-log {log!r} is not on the pod's writable /var/lib/fleet")
        check(any(v.endswith(":/var/lib/fleet") for v in s.get("volumes", [])),
              "wms-adapter: compose's /var/lib/fleet is not writable")
    entry = [a.replace('"$@"', '"$$@"') for a in c.get("command", [])] or None
    check(s.get("entrypoint") == entry, f"{name}: entrypoint {s.get('entrypoint')} != pod's command {entry}")
    # CYCLONEDDS_URI differs (the pod's loopback profile, compose's): checked below.
    env = {e["name"]: e["value"] for e in c.get("env", []) if e["name"] != "CYCLONEDDS_URI"}
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
    sc = c.get("securityContext", {})
    if sc.get("readOnlyRootFilesystem"):
        check(s.get("read_only") is True, f"{name}: the pod's root filesystem is read-only, compose's not")
    if sc.get("allowPrivilegeEscalation") is False:
        check("no-new-privileges" in s.get("security_opt", []), f"{name}: no security_opt no-new-privileges")

# The network: one project bridge network, each service in its own namespace on it.
check("fleet" in (doc.get("networks") or {}), "no project network `fleet` under networks:")
dds = [n for n in {**compose, **added} if n not in NOT_DDS]
for name, s in added.items():
    check(s.get("image", "").startswith("localhost/fleet-"), f"{name}: image {s.get('image')} is not one of ours")
    check(s.get("read_only") is True, f"{name}: the root filesystem is not read-only")
    check("no-new-privileges" in s.get("security_opt", []), f"{name}: no security_opt no-new-privileges")
    check(s.get("cap_drop") == ["ALL"], f"{name}: capabilities not dropped")
    check(all(v.endswith(":ro") for v in s.get("volumes", []) if "/etc/fleet" in v), f"{name}: /etc/fleet writable")
for name, s in {**compose, **added}.items():
    check("network_mode" not in s, f"{name}: network_mode {s.get('network_mode')}: every service joins `fleet`")
    check(s.get("networks") == ["fleet"], f"{name}: networks {s.get('networks')} != ['fleet']")
    ports = s.get("ports", [])
    if name in ("wms-adapter", "wms-adapter-2"):
        check(len(ports) == 1 and str(ports[0]).startswith("127.0.0.1:") and str(ports[0]).endswith(":8080"),
              f"{name}: ports {ports}: the API only, on the host's loopback")
    else:
        check(not ports, f"{name}: publishes {ports}")
check(compose.get("fleetctl", {}).get("environment", {}).get("FLEET_WMS_URL") == "https://wms-adapter:8080",
      "fleetctl: FLEET_WMS_URL is not https to the adapter's service name")
check(compose.get("fleetctl", {}).get("environment", {}).get("FLEET_WMS_CA_CERT") == "/etc/fleet/dds/ca.pem",
      "fleetctl: FLEET_WMS_CA_CERT is not the site CA")

# Secure by default: every DDS service of the files (the VDA 5050 overlay's bridge included) and of
# the Pod requires DDS Security and joins with its own identity, the profile first and the
# identity's security.xml from the site's files under /etc/fleet/dds; the adapter requires https.
# A second manager or adapter joins as the first one: the same role, the same identity.
IDENTITY = {"robot-agent": "agents", "fleet-sim": "simulator", "fleet-manager-2": "fleet-manager",
            "wms-adapter-2": "wms-adapter"}
full = {**compose, **overlay, **pg_overlay}
for name, s in full.items():
    env = dict(compose.get(name, {}).get("environment", {}) or {}, **(overlay.get(name, {}).get("environment") or {}),
               **(pg_overlay.get(name, {}).get("environment") or {}))
    if name not in dds:
        continue
    ident = IDENTITY.get(name, name)
    check(env.get("CYCLONEDDS_URI") == f"file:///usr/share/fleet/{PROFILE},file:///etc/fleet/dds/{ident}/security.xml",
          f"{name}: CYCLONEDDS_URI {env.get('CYCLONEDDS_URI')} is not the compose profile with its identity {ident}")
    check(env.get("FLEET_DDS_SECURITY") == "required", f"{name}: FLEET_DDS_SECURITY is not required")
    check(env.get("FLEET_DDS_SECURITY_DIR") == "/etc/fleet/dds", f"{name}: FLEET_DDS_SECURITY_DIR is not /etc/fleet/dds")
check(compose["wms-adapter"]["environment"].get("FLEET_WMS_TLS") == "required", "wms-adapter: FLEET_WMS_TLS is not required")
pod_vda = yaml.safe_load(open(f"{src}/deploy/fleet-pod.vda5050.yaml"))
for c in list(pod.values()) + pod_vda["containers"]:
    if c["name"] == "mosquitto":
        continue
    env = {e["name"]: e["value"] for e in c.get("env", [])}
    ident = IDENTITY.get(c["name"], c["name"])
    check(env.get("CYCLONEDDS_URI") == f"file:///usr/share/fleet/cyclonedds-local.xml,file:///etc/fleet/dds/{ident}/security.xml",
          f"pod {c['name']}: CYCLONEDDS_URI {env.get('CYCLONEDDS_URI')} is not the loopback profile with its identity")
    check(env.get("FLEET_DDS_SECURITY") == "required", f"pod {c['name']}: FLEET_DDS_SECURITY is not required")
check({"name": "FLEET_WMS_TLS", "value": "required"} in pod["wms-adapter"]["env"], "pod wms-adapter: FLEET_WMS_TLS is not required")
# The dev overlays: off for every DDS service (and https off for the adapter), the plain profile.
dev = {**yaml.safe_load(open(f"{src}/deploy/compose.dev.yaml"))["services"],
       **yaml.safe_load(open(f"{src}/deploy/compose.dev.vda5050.yaml"))["services"],
       **yaml.safe_load(open(f"{src}/deploy/compose.dev.postgres.yaml"))["services"]}
pod_dev = yaml.safe_load(open(f"{src}/deploy/fleet-pod.dev.yaml"))["env"]
for name in dds:
    env = dev.get(name, {}).get("environment", {})
    check(env.get("FLEET_DDS_SECURITY") == "off" and env.get("CYCLONEDDS_URI") == f"file:///usr/share/fleet/{PROFILE}",
          f"compose dev overlays: {name} keeps DDS Security")
    if name in pg_overlay:
        continue  # no pod of two managers and two adapters
    penv = {e["name"]: e["value"] for e in pod_dev.get(name, [])}
    check(penv.get("FLEET_DDS_SECURITY") == "off" and penv.get("CYCLONEDDS_URI") == "file:///usr/share/fleet/cyclonedds-local.xml",
          f"fleet-pod.dev.yaml: {name} keeps DDS Security")
check(dev["wms-adapter"]["environment"].get("FLEET_WMS_TLS") == "off", "compose.dev.yaml: the adapter keeps https")
check({"name": "FLEET_WMS_TLS", "value": "off"} in pod_dev["wms-adapter"], "fleet-pod.dev.yaml: the adapter keeps https")
check(not set(dev) - set(dds) - {"fleetctl"}, f"compose dev overlays name other services: {set(dev) - set(dds)}")

ns = {"c": "https://cdds.io/config"}
general = ET.parse(f"{src}/deploy/{PROFILE}").getroot().find("c:Domain", ns)
peers = [p.get("address") for p in general.findall("c:Discovery/c:Peers/c:Peer", ns)]
check(sorted(peers) == sorted(dds), f"{PROFILE}: peers {peers} != the DDS services {dds}")
check(general.findtext("c:General/c:AllowMulticast", namespaces=ns) == "false", f"{PROFILE}: multicast is not off")
runtime = open(f"{src}/deploy/runtime.Containerfile").read()
check(any(line.startswith("COPY ") and PROFILE in line and "/usr/share/fleet/" in line for line in runtime.splitlines()),
      f"deploy/runtime.Containerfile does not put {PROFILE} into /usr/share/fleet/")

for p in problems:
    print("compose.yaml:", p)
print(f"{len(pod)} services compared, {len(added)} of the VDA 5050 and PostgreSQL overlays checked, {len(peers)} DDS peers, {len(problems)} problems")
sys.exit(1 if problems else 0)
